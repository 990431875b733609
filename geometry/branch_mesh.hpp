// Branch meshes: generalized cylinders [Bloomenthal 1985] along a TreeGraph (Livny et al. 2011, §5).
//
// The tree is split into axes: an axis starts at the root (or at a fork, for a lateral child)
// and follows the main child (children[0]) to a tip, so the main continuation through a fork is
// one seamless tube. Each axis is a centripetal Catmull-Rom curve through its nodes; rings of
// `sides` vertices are placed along it with rotation-minimizing (parallel-transport) frames, so
// consecutive rings never twist. A lateral axis starts at the fork node on the parent's axis,
// with its first frame obtained by the minimal rotation of the parent's frame there, and its
// base ring no wider than the parent: the joint is buried inside the parent tube (no crack).
// Every tube is closed with flat caps, so each tube is a closed, outward-oriented surface.
#pragma once

#include "core/tree_graph.hpp"
#include "core/triangle_mesh.hpp"

namespace treelobes {

struct BranchMeshOptions {
    int sides = 8;                 // vertices per ring (3..64)
    int subdivisions = 2;          // rings per internode along the smooth curve (1 = a ring at each node only)
    float min_radius = 0.002f;     // metres; smaller radii (twig tips, allometric zeros) are raised to this
    float radius_scale = 1.0f;     // multiplies every node radius
    float min_axis_radius = 0.0f;  // metres; axes whose base radius is below this are left out (0 = keep all)
    bool cap_ends = true;          // close each tube at its base and tip
};

// Builds the tubes of every axis of `tree` (validated first; Error(InvalidInput) if it is not a
// rooted tree). The mesh has the tree's origin. A tree with fewer than two nodes gives an empty
// mesh. Throws Error(Usage) for options out of range.
TriangleMesh build_branch_mesh(const TreeGraph& tree, const BranchMeshOptions& options = {});

}  // namespace treelobes
