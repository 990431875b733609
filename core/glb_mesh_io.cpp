#include "core/glb_mesh_io.hpp"

#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/glb_container.hpp"
#include "core/little_endian.hpp"
#include "core/obj_mesh_io.hpp"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <string_view>
#include <tuple>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

using nlohmann::json;

// Component types (§3.6.2.2).
constexpr std::uint64_t kByte = 5120, kUnsignedByte = 5121, kShort = 5122, kUnsignedShort = 5123, kUnsignedInt = 5125, kFloat = 5126;
// Primitive modes (§3.7.2.1): 0-3 points and lines, 4-6 triangles.
constexpr std::uint64_t kTriangles = 4, kTriangleStrip = 5, kTriangleFan = 6;
// Deeper node hierarchies are refused rather than recursed into (real scenes have a few dozen).
constexpr int kMaxNodeDepth = 1000;
// Instancing (one mesh under many nodes) multiplies what the file holds; beyond this many
// vertices or triangles per byte of file the model is refused instead of allocated.
constexpr std::uint64_t kMaxElementsPerFileByte = 32;

bool is_supported_extension(const std::string& extension) {
    static constexpr std::string_view kSupported[] = {"KHR_mesh_quantization", "KHR_texture_transform", "KHR_texture_basisu",
                                                      "EXT_texture_webp", "EXT_texture_avif"};
    return std::find(std::begin(kSupported), std::end(kSupported), extension) != std::end(kSupported) ||
           extension.rfind("KHR_materials_", 0) == 0;
}

std::size_t component_bytes(std::uint64_t type) {
    switch (type) {
        case kByte:
        case kUnsignedByte:
            return 1;
        case kShort:
        case kUnsignedShort:
            return 2;
        case kUnsignedInt:
        case kFloat:
            return 4;
        default:
            return 0;
    }
}

std::size_t type_components(const std::string& type) {
    static const std::map<std::string, std::size_t> kComponents{{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4},
                                                                {"MAT2", 4},   {"MAT3", 9}, {"MAT4", 16}};
    const auto it = kComponents.find(type);
    return it == kComponents.end() ? 0 : it->second;
}

// The member `key` of `object`; nullptr when `object` is no JSON object or lacks it.
const json* member(const json& object, const char* key) {
    if (!object.is_object()) return nullptr;
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
}

std::string name_of(const json& object) {
    const json* name = member(object, "name");
    return name && name->is_string() ? name->get<std::string>() : std::string();
}

// The typed elements of one accessor inside the BIN chunk, bounds already checked.
struct AccessorData {
    const std::uint8_t* first = nullptr;
    std::size_t count = 0, stride = 0, components = 0;
    std::uint64_t component_type = 0;
    bool normalized = false;

    // Component `c` of element `i` as a number; normalized integers decoded as glTF 2.0 §3.11
    // (Animations) tabulates it.
    double component(std::size_t i, std::size_t c) const {
        const std::uint8_t* p = first + i * stride + c * component_bytes(component_type);
        switch (component_type) {
            case kByte:
                return normalized ? std::max(load<std::int8_t>(p) / 127.0, -1.0) : load<std::int8_t>(p);
            case kUnsignedByte:
                return normalized ? load<std::uint8_t>(p) / 255.0 : load<std::uint8_t>(p);
            case kShort:
                return normalized ? std::max(load<std::int16_t>(p) / 32767.0, -1.0) : load<std::int16_t>(p);
            case kUnsignedShort:
                return normalized ? load<std::uint16_t>(p) / 65535.0 : load<std::uint16_t>(p);
            case kUnsignedInt:
                return load<std::uint32_t>(p);
            default:
                return load<float>(p);
        }
    }
};

// A node showing a mesh, with the node's global transform (§3.5.3) and name.
struct MeshInstance {
    std::uint64_t mesh = 0;
    Eigen::Affine3d transform;
    std::string node_name;
};

struct TrianglePrimitive {
    std::string owner;  // "mesh M primitive P", for the messages
    std::uint64_t mode = kTriangles;
    std::uint64_t positions = 0;            // POSITION accessor
    std::optional<std::uint64_t> indices;   // indices accessor, none for non-indexed geometry
    std::size_t vertices = 0, corners = 0;  // POSITION count; index count (else vertices)
    std::string material;                   // the material's name

    std::size_t triangle_count() const { return mode == kTriangles ? corners / 3 : (corners < 3 ? 0 : corners - 2); }
};

struct MeshPrimitives {
    std::string name;
    std::vector<TrianglePrimitive> triangles;
    std::size_t skipped = 0;  // points and lines primitives, primitives without POSITION
};

class GlbMeshReader {
public:
    GlbMeshReader(const fs::path& path)
            : name_(path.string()), glb_(read_glb_container(path)), doc_(parse_glb_json(glb_, name_)), path_(path) {
        result_.report.format = "glb";
        max_elements_ = kMaxElementsPerFileByte * glb_.file_size();
    }

    NamedMesh read() {
        try {
            check_asset();
            for (const std::size_t root : scene_roots()) visit(root, Eigen::Affine3d::Identity(), 0);
            reserve_output();
            for (const MeshInstance& instance : instances_) add_instance(instance);
        } catch (const json::exception& e) {  // a member of an unexpected JSON type
            fail(std::string("glTF JSON lacks what a mesh needs: ") + e.what());
        }
        return finish();
    }

private:
    [[noreturn]] void fail(const std::string& what) const { throw Error::input(name_, what); }

    // A non-negative integer (glTF 2.0 "JSON Encoding" allows 1e2 or 100.0 for one).
    std::uint64_t unsigned_value(const json& value, const std::string& what) const {
        if (value.is_number_unsigned()) return value.get<std::uint64_t>();
        if (value.is_number_float()) {
            const double d = value.get<double>();
            if (d >= 0 && d < 9007199254740992.0 && d == std::floor(d)) return static_cast<std::uint64_t>(d);
        }
        fail(what + " is not a non-negative integer");
    }

    std::uint64_t unsigned_member(const json& object, const char* key, const std::string& owner,
                                  std::optional<std::uint64_t> fallback) const {
        if (const json* value = member(object, key)) return unsigned_value(*value, owner + " " + key);
        if (!fallback) fail(owner + " has no " + key);
        return *fallback;
    }

    // Element `index` of the top-level array `array` (§3.3: indices point to existing elements).
    const json& element(const char* array, std::uint64_t index, const std::string& referrer) const {
        const json* list = member(doc_, array);
        const std::size_t size = list && list->is_array() ? list->size() : 0;
        if (index >= size)
            fail(referrer + " refers to " + array + "[" + std::to_string(index) + "], but there are " + std::to_string(size));
        return (*list)[index];
    }

    void check_asset() const {
        const json* asset = member(doc_, "asset");
        const json* version = asset ? member(*asset, "version") : nullptr;
        if (!version || !version->is_string()) fail("glTF JSON has no asset.version");
        if (version->get<std::string>().rfind("2.", 0) != 0) fail("glTF version " + version->get<std::string>() + ", expected 2.x");
        if (const json* required = member(doc_, "extensionsRequired"); required && required->is_array())
            for (const json& extension : *required)
                if (!extension.is_string() || !is_supported_extension(extension.get<std::string>()))
                    fail("requires the glTF extension " + extension.dump() +
                         ", which treelobes does not read; export the model without it");
    }

    // §3.5.1: the scene `scene`, else the first scene, else (a library of nodes) every root node.
    std::vector<std::size_t> scene_roots() const {
        const json* scenes = member(doc_, "scenes");
        if (const json* scene = member(doc_, "scene"); scene || (scenes && scenes->is_array() && !scenes->empty())) {
            const std::uint64_t index = scene ? unsigned_value(*scene, "scene") : 0;
            const json& chosen = element("scenes", index, "scene");
            std::vector<std::size_t> roots;
            if (const json* nodes = member(chosen, "nodes"); nodes && nodes->is_array())
                for (const json& node : *nodes) roots.push_back(unsigned_value(node, "scene " + std::to_string(index) + " node"));
            return roots;
        }
        const json* nodes = member(doc_, "nodes");
        const std::size_t count = nodes && nodes->is_array() ? nodes->size() : 0;
        std::vector<char> is_child(count, 0);
        for (std::size_t n = 0; n < count; ++n)
            if (const json* children = member((*nodes)[n], "children"); children && children->is_array())
                for (const json& child : *children) {
                    const std::uint64_t c = unsigned_value(child, "node " + std::to_string(n) + " child");
                    if (c < count) is_child[c] = 1;
                }
        std::vector<std::size_t> roots;
        for (std::size_t n = 0; n < count; ++n)
            if (!is_child[n]) roots.push_back(n);
        return roots;
    }

    // `size` finite numbers of a node property.
    Eigen::VectorXd node_numbers(const json& values, std::size_t size, const std::string& what) const {
        if (!values.is_array() || values.size() != size) fail(what + " is not an array of " + std::to_string(size) + " numbers");
        Eigen::VectorXd numbers(static_cast<Eigen::Index>(size));
        for (std::size_t k = 0; k < size; ++k) {
            if (!values[k].is_number() || !std::isfinite(values[k].get<double>())) fail(what + " has a value that is not a finite number");
            numbers[static_cast<Eigen::Index>(k)] = values[k].get<double>();
        }
        return numbers;
    }

    // §3.5.3: `matrix` (column-major), else T * R * S.
    Eigen::Affine3d local_transform(const json& node, const std::string& owner) const {
        Eigen::Affine3d local = Eigen::Affine3d::Identity();
        if (const json* matrix = member(node, "matrix")) {
            local.matrix() = Eigen::Map<const Eigen::Matrix4d>(node_numbers(*matrix, 16, owner + " matrix").data());
            return local;
        }
        if (const json* t = member(node, "translation")) local.translate(Eigen::Vector3d(node_numbers(*t, 3, owner + " translation")));
        if (const json* r = member(node, "rotation")) {
            const Eigen::VectorXd q = node_numbers(*r, 4, owner + " rotation");
            const Eigen::Quaterniond rotation(q[3], q[0], q[1], q[2]);  // glTF stores x, y, z, w
            if (!(rotation.norm() > 1e-12)) fail(owner + " rotation is not a unit quaternion");
            local.rotate(rotation.normalized());
        }
        if (const json* s = member(node, "scale")) local.scale(Eigen::Vector3d(node_numbers(*s, 3, owner + " scale")));
        return local;
    }

    // §3.5.2: the hierarchy is a set of disjoint trees; a node met twice is a cycle or a shared child.
    void visit(std::size_t index, const Eigen::Affine3d& parent, int depth) {
        const std::string owner = "node " + std::to_string(index);
        const json& node = element("nodes", index, depth == 0 ? "the scene" : "a node's children");
        if (visited_.empty()) visited_.assign(member(doc_, "nodes")->size(), 0);
        if (visited_[index]) fail(owner + " is reached twice: the node hierarchy has a cycle or a shared child (glTF 2.0 §3.5.2)");
        if (depth >= kMaxNodeDepth) fail("node hierarchy deeper than " + std::to_string(kMaxNodeDepth) + " levels");
        visited_[index] = 1;
        const Eigen::Affine3d global = parent * local_transform(node, owner);
        if (const json* mesh = member(node, "mesh")) instances_.push_back({unsigned_value(*mesh, owner + " mesh"), global, name_of(node)});
        if (const json* children = member(node, "children"); children && children->is_array())
            for (const json& child : *children) visit(unsigned_value(child, owner + " child"), global, depth + 1);
    }

    // The triangle primitives of mesh `index`, checked once however many nodes show the mesh.
    const MeshPrimitives& primitives_of(std::uint64_t index) {
        if (const auto known = meshes_.find(index); known != meshes_.end()) return known->second;
        const std::string owner = "mesh " + std::to_string(index);
        const json& mesh = element("meshes", index, "a node");
        const json* primitives = member(mesh, "primitives");
        if (!primitives || !primitives->is_array()) fail(owner + " has no primitives");
        MeshPrimitives result;
        for (std::size_t p = 0; p < primitives->size(); ++p) {
            const json& primitive = (*primitives)[p];
            TrianglePrimitive triangles;
            triangles.owner = owner + " primitive " + std::to_string(p);
            triangles.mode = unsigned_member(primitive, "mode", triangles.owner, kTriangles);
            if (triangles.mode > kTriangleFan)
                fail(triangles.owner + " has mode " + std::to_string(triangles.mode) + ", not a glTF 2.0 mode");
            const json* attributes = member(primitive, "attributes");
            const json* position = attributes ? member(*attributes, "POSITION") : nullptr;
            if (triangles.mode < kTriangles || !position) {  // points, lines, or no geometry of its own (§3.7.2.1)
                ++result.skipped;
                continue;
            }
            triangles.positions = unsigned_value(*position, triangles.owner + " POSITION");
            triangles.vertices = triangles.corners = accessor_data(triangles.positions, true).count;
            if (const json* indices = member(primitive, "indices")) {
                triangles.indices = unsigned_value(*indices, triangles.owner + " indices");
                triangles.corners = accessor_data(*triangles.indices, false).count;
            }
            if (triangles.mode == kTriangles && triangles.corners % 3 != 0)
                fail(triangles.owner + " has " + std::to_string(triangles.corners) + " corners, not a multiple of 3");
            if (const json* material = member(primitive, "material"))
                triangles.material =
                        name_of(element("materials", unsigned_value(*material, triangles.owner + " material"), triangles.owner));
            result.triangles.push_back(std::move(triangles));
        }
        result.name = name_of(mesh);
        return meshes_.emplace(index, std::move(result)).first->second;
    }

    // Counts what the scene instantiates before anything is allocated.
    void reserve_output() {
        std::uint64_t vertices = 0, triangles = 0;
        for (const MeshInstance& instance : instances_) {
            const MeshPrimitives& mesh = primitives_of(instance.mesh);
            result_.report.primitives_skipped += mesh.skipped;
            for (const TrianglePrimitive& primitive : mesh.triangles) {
                vertices += primitive.vertices;
                triangles += primitive.triangle_count();
                if (vertices > max_elements_ || triangles > max_elements_)
                    fail("the scene instantiates more than " + std::to_string(kMaxElementsPerFileByte) +
                         " vertices or triangles per byte of the file");
            }
        }
        if (vertices > static_cast<std::uint64_t>(std::numeric_limits<int>::max())) fail("more vertices than a mesh can hold");
        result_.mesh.vertices.reserve(vertices);
        result_.mesh.faces.reserve(triangles);
        face_names_.reserve(triangles);
    }

    // The accessor `index` located in the BIN chunk, every offset, count and stride checked
    // against the buffer view and the chunk before use (§3.6.1, §3.6.2.4).
    AccessorData accessor_data(std::uint64_t index, bool vertex_attribute) const {
        const std::string owner = "accessor " + std::to_string(index);
        const json& accessor = element("accessors", index, "a primitive");
        if (member(accessor, "sparse")) fail(owner + " is sparse, which is not supported (glTF 2.0 §3.6.2.3)");
        const json* view_index = member(accessor, "bufferView");
        if (!view_index) fail(owner + " has no bufferView (data supplied by an extension is not supported)");
        AccessorData data;
        data.component_type = unsigned_member(accessor, "componentType", owner, std::nullopt);
        const json* type = member(accessor, "type");
        data.components = type && type->is_string() ? type_components(type->get<std::string>()) : 0;
        if (component_bytes(data.component_type) == 0 || data.components == 0) fail(owner + " has an unknown componentType or type");
        if (const json* normalized = member(accessor, "normalized"); normalized && normalized->is_boolean())
            data.normalized = normalized->get<bool>();
        const std::uint64_t count = unsigned_member(accessor, "count", owner, std::nullopt);
        const std::uint64_t accessor_offset = unsigned_member(accessor, "byteOffset", owner, 0);

        const std::uint64_t view_number = unsigned_value(*view_index, owner + " bufferView");
        const std::string view_owner = "bufferView " + std::to_string(view_number);
        const json& view = element("bufferViews", view_number, owner);
        const std::string_view bin = buffer_bytes(unsigned_member(view, "buffer", view_owner, std::nullopt), view_owner);
        const std::uint64_t view_offset = unsigned_member(view, "byteOffset", view_owner, 0);
        const std::uint64_t view_length = unsigned_member(view, "byteLength", view_owner, std::nullopt);
        if (view_offset > bin.size() || view_length > bin.size() - view_offset) fail(view_owner + " lies beyond its buffer");

        const std::uint64_t element_bytes = component_bytes(data.component_type) * data.components;
        std::uint64_t stride = element_bytes;
        if (const json* byte_stride = member(view, "byteStride"); byte_stride && vertex_attribute) {
            stride = unsigned_value(*byte_stride, view_owner + " byteStride");
            if (stride < element_bytes || stride > 252)
                fail(view_owner + " byteStride " + std::to_string(stride) + " does not fit " + owner);
        }
        // §3.6.2.4: byteOffset + stride * (count - 1) + element size <= bufferView.byteLength.
        if (count == 0) fail(owner + " has count 0");
        if (accessor_offset > view_length || element_bytes > view_length - accessor_offset ||
            count - 1 > (view_length - accessor_offset - element_bytes) / stride)
            fail(owner + " (" + std::to_string(count) + " elements) lies beyond " + view_owner);
        data.first = reinterpret_cast<const std::uint8_t*>(bin.data() + view_offset + accessor_offset);
        data.count = count;
        data.stride = stride;
        return data;
    }

    // §3.6.1.2: buffer 0 without uri is the GLB's BIN chunk; nothing else is read.
    std::string_view buffer_bytes(std::uint64_t index, const std::string& referrer) const {
        const json& buffer = element("buffers", index, referrer);
        if (const json* uri = member(buffer, "uri")) {
            const std::string text = uri->is_string() ? uri->get<std::string>() : uri->dump();
            if (text.rfind("data:", 0) == 0)
                fail("buffer " + std::to_string(index) + " is a data: URI; pack the model as a self-contained .glb");
            fail("buffer " + std::to_string(index) + " refers to '" + text.substr(0, 80) +
                 "': external buffers are not supported; pack the model as a self-contained .glb");
        }
        if (index != 0) fail("buffer " + std::to_string(index) + " has no uri but only buffer 0 is the GLB's BIN chunk");
        if (!glb_.has_bin()) fail("buffer 0 needs the GLB's BIN chunk, which the file lacks");
        const std::uint64_t length = unsigned_member(buffer, "byteLength", "buffer 0", std::nullopt);
        if (length > glb_.bin().size())
            fail("buffer 0 has byteLength " + std::to_string(length) + " but the BIN chunk holds " + std::to_string(glb_.bin().size()) +
                 " bytes");
        return glb_.bin().substr(0, length);
    }

    std::vector<Eigen::Vector3d> positions(std::uint64_t index) const {
        const AccessorData data = accessor_data(index, true);
        // Float, or KHR_mesh_quantization's (unsigned) bytes and shorts, normalized or not.
        if (data.components != 3 || data.component_type == kUnsignedInt)
            fail("POSITION accessor " + std::to_string(index) + " is not a VEC3 of float (or of KHR_mesh_quantization's bytes and shorts)");
        std::vector<Eigen::Vector3d> points(data.count);
        for (std::size_t i = 0; i < data.count; ++i) {
            points[i] = {data.component(i, 0), data.component(i, 1), data.component(i, 2)};
            if (!points[i].allFinite())
                fail("POSITION accessor " + std::to_string(index) + " element " + std::to_string(i) + " has a NaN/inf coordinate");
        }
        return points;
    }

    // The corner list of a primitive: its indices, else 0, 1, ... (non-indexed geometry).
    std::vector<std::uint32_t> corners(const TrianglePrimitive& primitive) const {
        std::vector<std::uint32_t> list(primitive.corners);
        if (!primitive.indices) {
            for (std::size_t i = 0; i < list.size(); ++i) list[i] = static_cast<std::uint32_t>(i);
            return list;
        }
        const std::uint64_t index = *primitive.indices;
        const AccessorData data = accessor_data(index, false);
        if (data.components != 1 || data.normalized ||
            (data.component_type != kUnsignedByte && data.component_type != kUnsignedShort && data.component_type != kUnsignedInt))
            fail("indices accessor " + std::to_string(index) + " is not a SCALAR of unsigned byte, short or int");
        for (std::size_t i = 0; i < data.count; ++i) {
            const double corner = data.component(i, 0);
            if (corner >= static_cast<double>(primitive.vertices))
                fail("indices accessor " + std::to_string(index) + " element " + std::to_string(i) + " is " +
                     std::to_string(static_cast<std::uint64_t>(corner)) + ", beyond the " + std::to_string(primitive.vertices) +
                     " vertices of " + primitive.owner);
            list[i] = static_cast<std::uint32_t>(corner);
        }
        return list;
    }

    void add_instance(const MeshInstance& instance) {
        const MeshPrimitives& mesh = primitives_of(instance.mesh);
        for (const TrianglePrimitive& primitive : mesh.triangles)
            add_primitive(primitive, instance.transform, names_index({primitive.material, mesh.name, instance.node_name}));
    }

    void add_primitive(const TrianglePrimitive& primitive, const Eigen::Affine3d& transform, std::uint32_t names) {
        const std::vector<std::uint32_t> c = corners(primitive);
        // §3.7.4: a transform with a negative determinant mirrors the mesh and turns its winding
        // clockwise; our faces stay counter-clockwise seen from outside.
        const bool mirrored = transform.linear().determinant() < 0;
        auto& vertices = result_.mesh.vertices;
        const std::size_t base = vertices.size();
        for (const Eigen::Vector3d& p : positions(primitive.positions)) {
            const Eigen::Vector3d y_up = transform * p;
            const Eigen::Vector3d z_up(y_up.x(), -y_up.z(), y_up.y());  // the inverse of export/gltf.cpp's y_up()
            if (!z_up.allFinite()) fail(primitive.owner + ": a node transform takes a vertex to a NaN/inf coordinate");
            if (vertices.empty()) local_origin_ = mesh_origin_for(z_up);
            vertices.push_back((z_up - local_origin_).cast<float>());
        }
        // §3.7.2.1 topologies: triangles {3i, 3i+1, 3i+2}; strips {i, i+1+i%2, i+2-i%2}; fans {i+1, i+2, 0}.
        for (std::size_t i = 0; i < primitive.triangle_count(); ++i) {
            std::array<std::uint32_t, 3> f{};
            if (primitive.mode == kTriangles)
                f = {c[3 * i], c[3 * i + 1], c[3 * i + 2]};
            else if (primitive.mode == kTriangleStrip)
                f = {c[i], c[i + 1 + i % 2], c[i + 2 - i % 2]};
            else
                f = {c[i + 1], c[i + 2], c[0]};
            if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
                ++result_.report.degenerate_faces;
                continue;
            }
            if (mirrored) std::swap(f[1], f[2]);
            result_.mesh.faces.push_back({static_cast<int>(base + f[0]), static_cast<int>(base + f[1]), static_cast<int>(base + f[2])});
            face_names_.push_back(names);
        }
    }

    std::uint32_t names_index(const FaceNames& names) {
        const auto [it, inserted] = index_of_.emplace(std::make_tuple(names.material, names.group, names.object),
                                                      static_cast<std::uint32_t>(result_.names.size()));
        if (inserted) result_.names.push_back(names);
        return it->second;
    }

    NamedMesh finish() {
        if (result_.mesh.faces.empty())
            fail("the glTF scene has no triangles" +
                 (result_.report.primitives_skipped == 0
                          ? std::string()
                          : " (" + std::to_string(result_.report.primitives_skipped) + " points or lines primitives skipped)"));
        // Our exports store coordinates relative to the scene origin kept in the sidecar.
        const auto sidecar = read_georef_sidecar(path_);
        result_.mesh.origin = (sidecar ? sidecar->origin : Eigen::Vector3d::Zero()) + local_origin_;
        result_.adopt_face_names(std::move(face_names_));
        return std::move(result_);
    }

    std::string name_;
    GlbContainer glb_;
    json doc_;
    fs::path path_;
    std::uint64_t max_elements_ = 0;
    std::vector<char> visited_;
    std::vector<MeshInstance> instances_;
    std::map<std::uint64_t, MeshPrimitives> meshes_;
    Eigen::Vector3d local_origin_ = Eigen::Vector3d::Zero();  // mesh_origin_for() of the first vertex (file frame)
    std::vector<std::uint32_t> face_names_;
    std::map<std::tuple<std::string, std::string, std::string>, std::uint32_t> index_of_;
    NamedMesh result_;
};

}  // namespace

NamedMesh read_glb(const fs::path& path) { return GlbMeshReader(path).read(); }

}  // namespace treelobes
