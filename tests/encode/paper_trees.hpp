// Skeletons built to match Strnad et al. 2020's figures, for the code vectors printed in the paper.
#pragma once

#include "core/tree_graph.hpp"

#include <array>
#include <cmath>

namespace treelobes::test {

// Fig. 4 / Fig. 6 at l = 1 m, r = 3 (voxel size 1/3 m). Voxel coordinates of the vertices
// (the figure's planar tree, y up):
//   v0 (0,0,0) root, v1 (0,3,0), v2 (0,6,0) fork, v3 (-1,8,0) fork, v4 (-2,11,0) tip,
//   v5 (2,8,0) fork (lateral of v2), v6 (3,10,0) tip, v7 (-4,8,0) tip (lateral of v3),
//   v8 (5,7,0) tip (lateral of v5).
// Positions are voxel centres plus offsets below half a voxel, relative to a root that is not
// at the origin; node indices are scrambled and children are stored laterals first, so the
// encoder has to find the main children itself (by radius).
inline constexpr double kFig4InternodeLength = 1.0;
inline constexpr double kFig4Resolution = 3.0;
inline constexpr const char* kFig4F6 = "11181116113611137001160117333700047";
inline constexpr const char* kFig4DBF6 = "11186346170011637333700047";

inline TreeGraph fig4_tree() {
    struct Vertex {
        int index;   // node index in the TreeGraph
        int parent;  // logical parent (v-number), -1 for the root
        int x, y;    // voxel coordinates
        float radius_mm;
    };
    // Radii: main children are thicker than their lateral siblings.
    const std::array<Vertex, 9> v = {{{0, -1, 0, 0, 12.f},
                                      {5, 0, 0, 3, 10.f},
                                      {3, 1, 0, 6, 9.f},
                                      {8, 2, -1, 8, 6.f},
                                      {1, 3, -2, 11, 3.f},
                                      {2, 2, 2, 8, 4.f},
                                      {7, 5, 3, 10, 3.f},
                                      {4, 3, -4, 8, 2.f},
                                      {6, 5, 5, 7, 1.f}}};
    const double d = kFig4InternodeLength / kFig4Resolution;
    const Eigen::Vector3d root(10.25, -3.5, 1.125);
    TreeGraph tree;
    tree.nodes.resize(v.size());
    for (std::size_t k = 0; k < v.size(); ++k) {
        // Offsets of up to 0.35 voxels so that Eq. 1 has to round, never on a voxel border.
        const Eigen::Vector3d offset =
                k == 0 ? Eigen::Vector3d::Zero()
                       : Eigen::Vector3d(0.35 * std::sin(3.0 * k), 0.35 * std::cos(5.0 * k), 0.3 * std::sin(k + 1.0));
        const Eigen::Vector3d p = root + d * (Eigen::Vector3d(v[k].x, v[k].y, 0) + offset);
        TreeNode& node = tree.nodes[v[k].index];
        node.position = p.cast<float>();
        node.radius = v[k].radius_mm * 0.001f;
        node.parent = v[k].parent < 0 ? -1 : v[v[k].parent].index;
    }
    // Children in reverse logical order: the lateral (later v-number) first.
    for (std::size_t k = v.size(); k-- > 1;) tree.nodes[v[v[k].parent].index].children.push_back(v[k].index);
    return tree;
}

}  // namespace treelobes::test
