// Triangle meshes of synthetic trees: the branch tubes of geometry/branch_mesh (generalized
// cylinders with smooth joints) plus one quad (two triangles) per leaf.
#pragma once

#include "geometry/branch_mesh.hpp"
#include "synth/grow.hpp"

namespace treelobes::synth {

struct TreeMeshOptions {
    BranchMeshOptions branches{8, 2, 0.001f, 1.0f, 0.0f, true};
    bool leaves = true;
};

// Leaf blades as triangles (two per leaf), in the tree's frame.
TriangleMesh leaf_mesh(const std::vector<Leaf>& leaves, LeafShape shape);

struct TreeMesh {
    TriangleMesh wood;
    TriangleMesh leaves;
    TriangleMesh combined() const;  // wood first, then leaves
};

TreeMesh tree_mesh(const SyntheticTree& tree, const TreeMeshOptions& options = {});

}  // namespace treelobes::synth
