#include "synth/ray_scene.hpp"

#include "core/error.hpp"

#include <Eigen/Geometry>
#include <embree3/rtcore.h>

#include <cmath>
#include <cstring>
#include <string>

namespace treelobes::synth {

namespace {

struct Label {
    int tree;
    int internode;
};

// Internode i (a skeleton node and the segment from its parent) of the scene's tree t.
struct InternodeRef {
    std::size_t t, i;
};

// A round curve is wider than the cone through its end radii by 1 / sqrt(1 - slope^2), the slope
// being the change of radius per unit length: 2 % at 0.2. Steeper internodes are traced as cones.
constexpr float kMaxRoundRadiusSlope = 0.2f;

// Leaves of one tree (or the understory) and where they go in the scene frame.
struct BladeSet {
    const std::vector<Leaf>* leaves;
    LeafShape shape;
    int tree;  // -1: understory
    Eigen::Vector3f offset;
};

[[noreturn]] void embree_failed(RTCDevice device, const std::string& what) {
    const RTCError code = device ? rtcGetDeviceError(device) : RTC_ERROR_UNKNOWN;
    const std::string reason = code == RTC_ERROR_OUT_OF_MEMORY ? "out of memory" : "error " + std::to_string(static_cast<int>(code));
    throw Error(ExitCode::Internal, "Embree: " + what + " failed (" + reason + ")");
}

template <typename T>
T* new_buffer(RTCDevice device, RTCGeometry geometry, RTCBufferType type, RTCFormat format, std::size_t count) {
    void* data = rtcSetNewGeometryBuffer(geometry, type, 0, format, sizeof(T), count);
    if (!data) embree_failed(device, "allocating a geometry buffer");
    return static_cast<T*>(data);
}

// Scene meshes carry no species: typical near-infrared reflectances of bark and leaves.
constexpr float kMeshBarkReflectance = 0.35f;
constexpr float kMeshLeafReflectance = 0.45f;

}  // namespace

struct RayScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    unsigned curves = RTC_INVALID_GEOMETRY_ID, cones = RTC_INVALID_GEOMETRY_ID, leaves = RTC_INVALID_GEOMETRY_ID;
    unsigned ground = RTC_INVALID_GEOMETRY_ID, understory = RTC_INVALID_GEOMETRY_ID, meshes = RTC_INVALID_GEOMETRY_ID;
    std::vector<Label> curve_labels, cone_labels, leaf_labels;
    std::vector<std::uint8_t> mesh_wood;  // per triangle of `meshes`
    std::vector<float> bark, foliage;     // reflectance per tree
    std::size_t primitives = 0;

    ~Impl() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }

    unsigned attach(RTCGeometry geometry) {
        rtcCommitGeometry(geometry);
        const unsigned id = rtcAttachGeometry(scene, geometry);
        rtcReleaseGeometry(geometry);
        return id;
    }

    // One segment per internode, from the parent node (radius at the parent end) to the node.
    // A round linear curve is the hull of the spheres at its two ends: it closes the joints of a
    // bending stem, but where the radius falls steeply (a fig's root flare: 1.49 m to 0.76 m over
    // 0.87 m) the hull hugs the wide sphere and the trunk bulges far above the node (its bark at
    // 1.0 m lay 1.13 m from the axis, not 0.74 m). Such internodes are plain capped cones.
    void add_branches(const Scene& s) {
        std::vector<InternodeRef> round, steep;
        for (std::size_t t = 0; t < s.trees.size(); ++t) {
            const auto& tree = s.trees[t].tree;
            for (std::size_t i = 1; i < tree.skeleton.size(); ++i) {
                const auto& node = tree.skeleton.nodes[i];
                const float length = (node.position - tree.skeleton.nodes[node.parent].position).norm();
                const float fall = std::abs(tree.internode_start_radius[i] - node.radius);
                (fall > kMaxRoundRadiusSlope * length ? steep : round).push_back({t, i});
            }
        }
        curves = add_internodes(s, round, RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE, curve_labels);
        cones = add_internodes(s, steep, RTC_GEOMETRY_TYPE_CONE_LINEAR_CURVE, cone_labels);
    }

    unsigned add_internodes(const Scene& s, const std::vector<InternodeRef>& internodes, RTCGeometryType type, std::vector<Label>& labels) {
        if (internodes.empty()) return RTC_INVALID_GEOMETRY_ID;
        const std::size_t count = internodes.size();
        RTCGeometry g = rtcNewGeometry(device, type);
        auto* vertices = new_buffer<float[4]>(device, g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT4, 2 * count);
        auto* index = new_buffer<unsigned>(device, g, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT, count);
        for (std::size_t k = 0; k < count; ++k) {
            const auto [t, i] = internodes[k];
            const auto& tree = s.trees[t].tree;
            const Eigen::Vector3f at = s.trees[t].position.cast<float>();
            const auto& node = tree.skeleton.nodes[i];
            const Eigen::Vector3f a = at + tree.skeleton.nodes[node.parent].position, b = at + node.position;
            const float ra = tree.internode_start_radius[i], rb = node.radius;
            std::memcpy(vertices[2 * k], std::array<float, 4>{a.x(), a.y(), a.z(), ra}.data(), 16);
            std::memcpy(vertices[2 * k + 1], std::array<float, 4>{b.x(), b.y(), b.z(), rb}.data(), 16);
            index[k] = static_cast<unsigned>(2 * k);
            labels.push_back({static_cast<int>(t), static_cast<int>(i)});
        }
        primitives += count;
        return attach(g);
    }

    unsigned add_blades(const std::vector<BladeSet>& sets, std::vector<Label>* labels) {
        std::size_t count = 0;
        for (const auto& set : sets) count += set.leaves->size();
        if (count == 0) return RTC_INVALID_GEOMETRY_ID;
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_QUAD);
        auto* vertices = new_buffer<float[3]>(device, g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3, 4 * count);
        auto* index = new_buffer<unsigned[4]>(device, g, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT4, count);
        std::size_t k = 0;
        for (const auto& set : sets) {
            for (const Leaf& leaf : *set.leaves) {
                const auto corners = leaf_corners(leaf, set.shape);
                for (int c = 0; c < 4; ++c) {
                    const Eigen::Vector3f p = set.offset + corners[c];
                    vertices[4 * k + c][0] = p.x();
                    vertices[4 * k + c][1] = p.y();
                    vertices[4 * k + c][2] = p.z();
                    index[k][c] = static_cast<unsigned>(4 * k + c);
                }
                if (labels) labels->push_back({set.tree, leaf.internode});
                ++k;
            }
        }
        primitives += count;
        return attach(g);
    }

    // All scene meshes as one triangle geometry, each triangle labelled wood or leaf.
    void add_meshes(const Scene& s) {
        std::size_t vertex_count = 0, face_count = 0;
        for (const auto& m : s.meshes) {
            if (m.wood.size() != m.mesh.faces.size()) throw Error(ExitCode::Internal, "scene mesh: one wood label per face expected");
            vertex_count += m.mesh.vertices.size();
            face_count += m.mesh.faces.size();
        }
        if (face_count == 0) return;
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vertices = new_buffer<float[3]>(device, g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3, vertex_count);
        auto* index = new_buffer<unsigned[3]>(device, g, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT3, face_count);
        std::size_t v = 0, f = 0;
        for (const auto& m : s.meshes) {
            const Eigen::Vector3f offset = (m.mesh.origin - s.origin).cast<float>();
            const auto base = static_cast<unsigned>(v);
            for (const auto& p : m.mesh.vertices) {
                const Eigen::Vector3f q = offset + p;
                vertices[v][0] = q.x(), vertices[v][1] = q.y(), vertices[v][2] = q.z();
                ++v;
            }
            for (std::size_t k = 0; k < m.mesh.faces.size(); ++k, ++f) {
                for (int c = 0; c < 3; ++c) index[f][c] = base + static_cast<unsigned>(m.mesh.faces[k][c]);
                mesh_wood.push_back(m.wood[k]);
            }
        }
        primitives += face_count;
        meshes = attach(g);
    }

    void add_ground(const Heightfield& h) {
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        const std::size_t cells = static_cast<std::size_t>(h.nx - 1) * (h.ny - 1);
        auto* vertices = new_buffer<float[3]>(device, g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3, h.z.size());
        auto* index = new_buffer<unsigned[3]>(device, g, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT3, 2 * cells);
        for (int j = 0; j < h.ny; ++j)
            for (int i = 0; i < h.nx; ++i) {
                float* v = vertices[static_cast<std::size_t>(j) * h.nx + i];
                v[0] = static_cast<float>(h.x0 + i * h.cell);
                v[1] = static_cast<float>(h.y0 + j * h.cell);
                v[2] = h.at(i, j);
            }
        std::size_t k = 0;
        for (int j = 0; j + 1 < h.ny; ++j)
            for (int i = 0; i + 1 < h.nx; ++i) {
                const unsigned a = static_cast<unsigned>(j * h.nx + i), b = a + 1, c = a + static_cast<unsigned>(h.nx), d = c + 1;
                index[k][0] = a, index[k][1] = b, index[k][2] = d, ++k;
                index[k][0] = a, index[k][1] = d, index[k][2] = c, ++k;
            }
        primitives += 2 * cells;
        ground = attach(g);
    }
};

RayScene::RayScene(const Scene& s) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.device = rtcNewDevice("verbose=0");
    if (!m.device) throw Error(ExitCode::Internal, "Embree: cannot create a device (unsupported CPU?)");
    m.scene = rtcNewScene(m.device);
    // Robust mode: rays through shared triangle edges of the ground never slip through.
    rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(m.scene, RTC_BUILD_QUALITY_MEDIUM);

    for (const auto& placed : s.trees) {
        m.bark.push_back(placed.tree.bark_reflectance);
        m.foliage.push_back(placed.tree.leaf_reflectance);
    }
    m.add_branches(s);

    std::vector<BladeSet> sets;
    for (std::size_t t = 0; t < s.trees.size(); ++t)
        sets.push_back({&s.trees[t].tree.leaves, s.trees[t].tree.leaf_shape, static_cast<int>(t), s.trees[t].position.cast<float>()});
    m.leaves = m.add_blades(sets, &m.leaf_labels);
    if (!s.understory.empty()) m.understory = m.add_blades({{&s.understory, s.understory_shape, -1, Eigen::Vector3f::Zero()}}, nullptr);
    if (s.ground) m.add_ground(*s.ground);
    m.add_meshes(s);

    rtcCommitScene(m.scene);
    if (rtcGetDeviceError(m.device) != RTC_ERROR_NONE) embree_failed(m.device, "building the ray-tracing scene");
}

RayScene::~RayScene() = default;

std::size_t RayScene::primitive_count() const { return impl_->primitives; }

bool RayScene::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near, float t_far, RayHit& hit) const {
    const Impl& m = *impl_;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit r{};
    r.ray.org_x = origin.x(), r.ray.org_y = origin.y(), r.ray.org_z = origin.z();
    r.ray.dir_x = direction.x(), r.ray.dir_y = direction.y(), r.ray.dir_z = direction.z();
    r.ray.tnear = t_near;
    r.ray.tfar = t_far;
    r.ray.mask = 0xFFFFFFFFu;
    r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(m.scene, &context, &r);
    if (r.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

    hit.t = r.ray.tfar;
    Eigen::Vector3f n(r.hit.Ng_x, r.hit.Ng_y, r.hit.Ng_z);
    const float length = n.norm();
    hit.normal = length > 0 ? Eigen::Vector3f(n / length) : Eigen::Vector3f(-direction);
    hit.tree = -1;
    hit.internode = -1;
    if (r.hit.geomID == m.curves || r.hit.geomID == m.cones) {
        const Label& label = (r.hit.geomID == m.curves ? m.curve_labels : m.cone_labels)[r.hit.primID];
        hit.surface = Surface::Wood;
        hit.tree = label.tree;
        hit.internode = label.internode;
        hit.reflectance = m.bark[static_cast<std::size_t>(label.tree)];
    } else if (r.hit.geomID == m.leaves) {
        const Label& label = m.leaf_labels[r.hit.primID];
        hit.surface = Surface::Leaf;
        hit.tree = label.tree;
        hit.internode = label.internode;
        hit.reflectance = m.foliage[static_cast<std::size_t>(label.tree)];
    } else if (r.hit.geomID == m.meshes) {
        const bool wood = m.mesh_wood[r.hit.primID] != 0;
        hit.surface = wood ? Surface::Wood : Surface::Leaf;
        hit.reflectance = wood ? kMeshBarkReflectance : kMeshLeafReflectance;
    } else if (r.hit.geomID == m.understory) {
        hit.surface = Surface::Understory;
        hit.reflectance = 0.5f;
    } else {
        hit.surface = Surface::Ground;
        hit.reflectance = 0.3f;
    }
    return true;
}

}  // namespace treelobes::synth
