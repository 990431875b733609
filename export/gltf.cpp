#include "export/gltf.hpp"

#include "core/error.hpp"
#include "core/glb_container.hpp"
#include "core/version.hpp"
#include "render/image.hpp"
#include "render/leaf_texture.hpp"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>

namespace treelobes::exporting {

namespace {

using nlohmann::json;

constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kLinear = 9729, kLinearMipmapLinear = 9987, kClampToEdge = 33071;
constexpr int kLeafTextureSize = 64;

// Our z-up frame to glTF's y-up frame.
Eigen::Vector3f y_up(const Eigen::Vector3f& p) { return {p.x(), p.z(), -p.y()}; }

// The mesh's vertex normals in glTF's y-up frame; vertices without faces get +y.
std::vector<Eigen::Vector3f> vertex_normals(const TriangleMesh& mesh) {
    std::vector<Eigen::Vector3f> normals = mesh.vertex_normals();
    for (auto& n : normals) n = n.isZero() ? Eigen::Vector3f::UnitY() : y_up(n).normalized();
    return normals;
}

class GlbBuilder {
public:
    // A primitive of `mesh` (tree frame) with `material`; `uvs` (one per vertex) become TEXCOORD_0.
    json primitive(const TriangleMesh& mesh, int material, const std::vector<Eigen::Vector2f>& uvs = {}) {
        std::vector<Eigen::Vector3f> positions;
        positions.reserve(mesh.vertices.size());
        for (const auto& v : mesh.vertices) positions.push_back(y_up(v));
        std::vector<std::uint32_t> indices;
        indices.reserve(mesh.faces.size() * 3);
        for (const auto& f : mesh.faces)
            for (int v : f) indices.push_back(static_cast<std::uint32_t>(v));
        json attributes = {{"POSITION", vec3_accessor(positions, true)}, {"NORMAL", vec3_accessor(vertex_normals(mesh), false)}};
        if (!uvs.empty()) {
            if (uvs.size() != mesh.vertices.size()) throw Error(ExitCode::Internal, "glTF: texture coordinates do not match the vertices");
            attributes["TEXCOORD_0"] = vec2_accessor(uvs);
        }
        return {{"attributes", attributes}, {"indices", index_accessor(indices)}, {"material", material}, {"mode", 4}};
    }

    // An image stored in the BIN chunk (glTF 2.0 §3.8.4: bufferView + mimeType); its index.
    int png_image(const std::string& png) {
        const int view = add_view(png.data(), png.size(), 0);
        while (bin.size() % 4) bin += '\0';  // the next view starts 4-aligned
        images.push_back({{"bufferView", view}, {"mimeType", "image/png"}});
        return static_cast<int>(images.size()) - 1;
    }

    json images = json::array();

    json buffer_views = json::array(), accessors = json::array();
    std::string bin;

private:
    // target 0: no target (images).
    int add_view(const void* data, std::size_t bytes, int target) {
        const std::size_t offset = bin.size();  // always a multiple of 4: floats, uint32 and padded images
        bin.append(static_cast<const char*>(data), bytes);
        json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
        if (target) view["target"] = target;
        buffer_views.push_back(view);
        return static_cast<int>(buffer_views.size()) - 1;
    }

    int vec2_accessor(const std::vector<Eigen::Vector2f>& values) {
        const int view = add_view(values.data(), values.size() * sizeof(Eigen::Vector2f), kArrayBuffer);
        accessors.push_back({{"bufferView", view}, {"componentType", kFloat}, {"count", values.size()}, {"type", "VEC2"}});
        return static_cast<int>(accessors.size()) - 1;
    }

    int vec3_accessor(const std::vector<Eigen::Vector3f>& values, bool bounds) {
        const int view = add_view(values.data(), values.size() * sizeof(Eigen::Vector3f), kArrayBuffer);
        json accessor = {{"bufferView", view}, {"componentType", kFloat}, {"count", values.size()}, {"type", "VEC3"}};
        if (bounds) {
            Eigen::Vector3f lo = values.front(), hi = values.front();
            for (const auto& v : values) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
            accessor["min"] = {lo.x(), lo.y(), lo.z()};
            accessor["max"] = {hi.x(), hi.y(), hi.z()};
        }
        accessors.push_back(accessor);
        return static_cast<int>(accessors.size()) - 1;
    }

    int index_accessor(const std::vector<std::uint32_t>& indices) {
        const int view = add_view(indices.data(), indices.size() * sizeof(std::uint32_t), kElementArrayBuffer);
        accessors.push_back({{"bufferView", view}, {"componentType", kUnsignedInt}, {"count", indices.size()}, {"type", "SCALAR"}});
        return static_cast<int>(accessors.size()) - 1;
    }
};

// bark, foliage (lobes) and, when leaf cards are present, leaves: texture 0 with an alpha mask
// (glTF 2.0 §3.9.4: MASK renders texels with alpha >= alphaCutoff opaque, drops the others).
json materials(bool leaves) {
    const auto material = [](const char* name, std::array<double, 4> colour, double roughness, bool two_sided) {
        json m = {{"name", name},
                  {"pbrMetallicRoughness", {{"baseColorFactor", colour}, {"metallicFactor", 0.0}, {"roughnessFactor", roughness}}}};
        if (two_sided) m["doubleSided"] = true;
        return m;
    };
    json list =
            json::array({material("bark", {0.36, 0.25, 0.16, 1.0}, 0.9, false), material("foliage", {0.22, 0.45, 0.14, 1.0}, 0.8, true)});
    if (leaves) {
        json leaf = material("leaves", {1.0, 1.0, 1.0, 1.0}, 0.8, true);
        leaf["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
        leaf["alphaMode"] = "MASK";
        leaf["alphaCutoff"] = 0.5;
        list.push_back(leaf);
    }
    return list;
}
constexpr int kBark = 0, kFoliage = 1, kLeaves = 2;

bool has_leaf_cards(const std::vector<GltfTree>& trees) {
    for (const auto& tree : trees)
        for (const auto& lod : tree.lods)
            if (!lod.foliage_uvs.empty() && !lod.foliage.faces.empty()) return true;
    return false;
}

void put_u32(std::string& out, std::uint32_t v) {
    for (int k = 0; k < 4; ++k) out += static_cast<char>((v >> (8 * k)) & 0xFF);
}

std::string assemble_glb(const json& document, std::string bin) {
    std::string text = document.dump();
    while (text.size() % 4) text += ' ';
    while (bin.size() % 4) bin += '\0';
    std::string out;
    put_u32(out, kGlbMagic);
    put_u32(out, 2);
    put_u32(out, static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
    put_u32(out, static_cast<std::uint32_t>(text.size()));
    put_u32(out, kGlbJsonChunk);
    out += text;
    put_u32(out, static_cast<std::uint32_t>(bin.size()));
    put_u32(out, kGlbBinChunk);
    out += bin;
    return out;
}

}  // namespace

std::string glb_bytes(const std::vector<GltfTree>& trees, const Eigen::Vector3d& scene_origin) {
    GlbBuilder builder;
    const bool leaves = has_leaf_cards(trees);
    json meshes = json::array(), nodes = json::array(), scene_nodes = json::array();
    for (const GltfTree& tree : trees) {
        if (tree.lods.empty() || (tree.lods.front().wood.faces.empty() && tree.lods.front().foliage.faces.empty())) continue;
        const Eigen::Vector3f shift = y_up((tree.origin - scene_origin).cast<float>());
        std::vector<int> lod_meshes;
        for (std::size_t k = 0; k < tree.lods.size(); ++k) {
            json primitives = json::array();
            if (!tree.lods[k].wood.faces.empty()) primitives.push_back(builder.primitive(tree.lods[k].wood, kBark));
            const TreeLod& lod = tree.lods[k];
            if (!lod.foliage.faces.empty())
                primitives.push_back(lod.foliage_uvs.empty() ? builder.primitive(lod.foliage, kFoliage)
                                                             : builder.primitive(lod.foliage, kLeaves, lod.foliage_uvs));
            if (primitives.empty()) {  // nothing left at this LOD: show the previous one
                lod_meshes.push_back(lod_meshes.back());
                continue;
            }
            meshes.push_back({{"name", tree.name + (k ? "_lod" + std::to_string(k) : "")}, {"primitives", primitives}});
            lod_meshes.push_back(static_cast<int>(meshes.size()) - 1);
        }
        const auto node_of = [&](std::size_t k) {
            json node = {{"name", tree.name + (k ? "_lod" + std::to_string(k) : "")}, {"mesh", lod_meshes[k]}};
            if (!shift.isZero()) node["translation"] = {shift.x(), shift.y(), shift.z()};
            return node;
        };
        json main = node_of(0);
        json extras = json::object();
        for (const auto& [key, value] : tree.extras) extras[key] = value;
        if (!tree.species.empty()) extras["species"] = tree.species;
        const int main_index = static_cast<int>(nodes.size());
        nodes.push_back(json());
        if (tree.lods.size() > 1) {
            json ids = json::array(), coverage = json::array();
            for (std::size_t k = 1; k < tree.lods.size(); ++k) {
                ids.push_back(static_cast<int>(nodes.size()));
                nodes.push_back(node_of(k));
            }
            // Screen fraction above which each LOD shows (LOD 0 first), the last one down to 0.
            for (std::size_t k = 0; k < tree.lods.size(); ++k)
                coverage.push_back(k + 1 == tree.lods.size() ? 0.0 : 0.25 / std::pow(4.0, static_cast<double>(k)));
            main["extensions"] = {{"MSFT_lod", {{"ids", ids}}}};
            extras["MSFT_screencoverage"] = coverage;
        }
        if (!extras.empty()) main["extras"] = extras;
        nodes[main_index] = main;
        scene_nodes.push_back(main_index);
    }
    if (scene_nodes.empty()) throw Error::input("", "glTF export: no tree has any geometry");
    if (leaves) builder.png_image(render::encode_png(render::leaf_texture(kLeafTextureSize)));  // once, after the geometry
    json document = {{"asset", {{"version", "2.0"}, {"generator", std::string("treelobes ") + kVersion}}},
                     {"scene", 0},
                     {"scenes", json::array({{{"name", "trees"}, {"nodes", scene_nodes}}})},
                     {"nodes", nodes},
                     {"meshes", meshes},
                     {"materials", materials(leaves)},
                     {"accessors", builder.accessors},
                     {"bufferViews", builder.buffer_views},
                     {"buffers", json::array({{{"byteLength", builder.bin.size()}}})}};
    if (leaves) {
        document["images"] = builder.images;
        document["samplers"] = json::array(
                {{{"magFilter", kLinear}, {"minFilter", kLinearMipmapLinear}, {"wrapS", kClampToEdge}, {"wrapT", kClampToEdge}}});
        document["textures"] = json::array({{{"sampler", 0}, {"source", 0}, {"name", "leaf"}}});
    }
    if (nodes.size() > scene_nodes.size()) document["extensionsUsed"] = {"MSFT_lod"};
    return assemble_glb(document, std::move(builder.bin));
}

}  // namespace treelobes::exporting
