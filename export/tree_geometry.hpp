// Renderable geometry of a tree at several levels of detail: branch tubes (generalized
// cylinders, geometry/branch_mesh.hpp) and foliage (the tree's lobes, or leaf cards at the
// twig tips of a bare skeleton).
//
// LOD k of n (k = 0 is full detail) keeps the branch axes whose base radius reaches the k/n
// quantile of the skeleton's node radii (the rule of Strnad et al. 2020's chain-code LOD,
// §3.2, applied to the mesh: a lateral thinner than the threshold goes with all it carries),
// with fewer tube sides (8, 6, 4, ...). Foliage: lobes are kept at every LOD; leaf cards are
// thinned to every 2^k-th tip and enlarged by sqrt(2^k), so the leaf area stays about the same.
#pragma once

#include "core/triangle_mesh.hpp"
#include "export/tree_input.hpp"

#include <vector>

namespace treelobes::exporting {

struct TreeGeometryOptions {
    int lods = 3;             // levels of detail (1..8)
    int sides = 8;            // tube sides at LOD 0 (3..64)
    bool leaves = true;       // leaf cards at the tips of skeletons without lobes
    double leaf_size = 0.08;  // metres: edge of a leaf card at LOD 0
};

struct TreeLod {
    TriangleMesh wood;     // closed tubes, origin = the tree's origin
    TriangleMesh foliage;  // lobes (closed) or leaf cards (two crossed quads per tip, two-sided)
    // Leaf cards only: texture coordinates per foliage vertex, glTF convention (v down): the
    // card's base edge at v = 1, its outer edge at v = 0, so a leaf texture's stalk sits on the twig.
    std::vector<Eigen::Vector2f> foliage_uvs;
};

// Throws Error(Usage) for options out of range.
std::vector<TreeLod> tree_lods(const ExportTree& tree, const TreeGeometryOptions& options = {});

// The tubes and lobes of LOD 0 in one mesh (PLY/OBJ export), origin = the tree's origin.
TriangleMesh tree_mesh(const ExportTree& tree, const TreeGeometryOptions& options = {});

}  // namespace treelobes::exporting
