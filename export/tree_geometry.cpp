#include "export/tree_geometry.hpp"

#include "core/error.hpp"
#include "geometry/branch_mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace treelobes::exporting {

namespace {

void check(const TreeGeometryOptions& o) {
    if (o.lods < 1 || o.lods > 8) throw Error::usage("export: --lods must be in 1..8, got " + std::to_string(o.lods));
    if (o.sides < 3 || o.sides > 64) throw Error::usage("export: --sides must be in 3..64, got " + std::to_string(o.sides));
    if (!(o.leaf_size > 0) || !std::isfinite(o.leaf_size)) throw Error::usage("export: --leaf-size must be > 0");
}

// Radius threshold of LOD k: the k/n quantile of the node radii (0 for LOD 0).
float lod_threshold(const TreeGraph& tree, int k, int n) {
    if (k == 0 || tree.empty()) return 0.0f;
    std::vector<float> radii;
    for (const auto& node : tree.nodes) radii.push_back(node.radius);
    std::sort(radii.begin(), radii.end());
    return radii[std::min(radii.size() - 1, radii.size() * static_cast<std::size_t>(k) / static_cast<std::size_t>(n))];
}

// Two crossed square cards per tip, along the tip's internode, beyond the tip; every
// `stride`-th tip in pre-order. `uvs` gets the texture coordinates of the cards' corners.
TriangleMesh leaf_cards(const TreeGraph& tree, int stride, float size, std::vector<Eigen::Vector2f>& uvs) {
    TriangleMesh cards;
    cards.origin = tree.origin;
    int tip = 0;
    for (int node : tree.preorder()) {
        const TreeNode& n = tree.nodes[node];
        if (!n.children.empty() || n.parent < 0 || tip++ % stride != 0) continue;
        Eigen::Vector3f along = n.position - tree.nodes[n.parent].position;
        if (along.norm() < 1e-6f) continue;
        along.normalize();
        const Eigen::Vector3f helper = std::abs(along.z()) < 0.9f ? Eigen::Vector3f::UnitZ() : Eigen::Vector3f::UnitX();
        const Eigen::Vector3f across = along.cross(helper).normalized();
        const Eigen::Vector3f across2 = along.cross(across).normalized();
        for (const Eigen::Vector3f& side : {across, across2}) {
            const int base = static_cast<int>(cards.vertices.size());
            const Eigen::Vector3f half = side * (0.5f * size);
            cards.vertices.push_back(n.position - half);
            cards.vertices.push_back(n.position + half);
            cards.vertices.push_back(n.position + half + along * size);
            cards.vertices.push_back(n.position - half + along * size);
            uvs.insert(uvs.end(), {{0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}, {0.0f, 0.0f}});
            cards.faces.push_back({base, base + 1, base + 2});
            cards.faces.push_back({base, base + 2, base + 3});
        }
    }
    return cards;
}

TriangleMesh branch_tubes(const ExportTree& tree, int sides, int subdivisions, float min_axis_radius) {
    BranchMeshOptions options;
    options.sides = sides;
    options.subdivisions = subdivisions;
    options.min_axis_radius = min_axis_radius;
    TriangleMesh mesh = build_branch_mesh(tree.skeleton, options);
    mesh.origin = tree.skeleton.origin;
    return mesh;
}

TriangleMesh lobes_mesh(const ExportTree& tree) {
    TriangleMesh all;
    all.origin = tree.skeleton.origin;
    for (const auto& lobe : tree.lobes) all.append(lobe);
    return all;
}

}  // namespace

std::vector<TreeLod> tree_lods(const ExportTree& tree, const TreeGeometryOptions& options) {
    check(options);
    std::vector<TreeLod> lods;
    for (int k = 0; k < options.lods; ++k) {
        TreeLod lod;
        const int sides = std::max(3, options.sides - 2 * k);
        lod.wood = branch_tubes(tree, sides, k == 0 ? 2 : 1, lod_threshold(tree.skeleton, k, options.lods));
        if (!tree.lobes.empty())
            lod.foliage = lobes_mesh(tree);
        else if (options.leaves) {
            const int stride = 1 << k;
            lod.foliage = leaf_cards(tree.skeleton, stride, static_cast<float>(options.leaf_size * std::sqrt(stride)), lod.foliage_uvs);
        }
        lods.push_back(std::move(lod));
    }
    return lods;
}

TriangleMesh tree_mesh(const ExportTree& tree, const TreeGeometryOptions& options) {
    check(options);
    TriangleMesh mesh = branch_tubes(tree, options.sides, 2, 0.0f);
    mesh.append(lobes_mesh(tree));
    return mesh;
}

}  // namespace treelobes::exporting
