#include "synth/tree_mesh.hpp"

namespace treelobes::synth {

TriangleMesh leaf_mesh(const std::vector<Leaf>& leaves, LeafShape shape) {
    TriangleMesh mesh;
    mesh.vertices.reserve(4 * leaves.size());
    mesh.faces.reserve(2 * leaves.size());
    for (const Leaf& leaf : leaves) {
        const int base = static_cast<int>(mesh.vertices.size());
        for (const auto& corner : leaf_corners(leaf, shape)) mesh.vertices.push_back(corner);
        // Corners run counter-clockwise seen from the side the normal points to.
        mesh.faces.push_back({base, base + 1, base + 2});
        mesh.faces.push_back({base, base + 2, base + 3});
    }
    return mesh;
}

TriangleMesh TreeMesh::combined() const {
    TriangleMesh all = wood;
    all.append(leaves);
    return all;
}

NamedMesh TreeMesh::named() const {
    NamedMesh out;
    out.mesh = combined();
    out.names = {{"bark", "branches", "tree"}, {"leaf", "leaves", "tree"}};
    out.face_names.assign(wood.faces.size(), 0);
    out.face_names.resize(out.mesh.faces.size(), 1);
    return out;
}

TreeMesh tree_mesh(const SyntheticTree& tree, const TreeMeshOptions& options) {
    TreeMesh mesh;
    mesh.wood = build_branch_mesh(tree.skeleton, options.branches);
    if (options.leaves) {
        mesh.leaves = leaf_mesh(tree.leaves, tree.leaf_shape);
        mesh.leaves.origin = tree.skeleton.origin;
    }
    return mesh;
}

}  // namespace treelobes::synth
