// Per-point tree labels shared by both segmentations: which points may belong to a tree, how
// densely they cover the ground, and the labels turned into a list of trees.
#pragma once

#include "core/point_cloud.hpp"
#include "segment/segment_trees.hpp"
#include "segment/terrain.hpp"

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace treelobes {

// Points that may belong to a tree: not ground, not of a class that is never a tree's (noise,
// buildings, water, wires, ...: core/asprs_classes.hpp), at least `clearance` above the DTM.
std::vector<std::uint8_t> vegetation_points(const PointCloud& cloud, const Terrain& terrain, float clearance);

// The vegetation points and the square cells of edge `cell` (metres) that hold any of them.
struct OccupiedCells {
    std::size_t points = 0;
    std::size_t cells = 0;
    // Points per square metre over the occupied cells (0 without vegetation).
    double density(double cell) const { return cells ? static_cast<double>(points) / (static_cast<double>(cells) * cell * cell) : 0.0; }
};

OccupiedCells occupied_cells(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation, float cell);

// Per-point labels 1..labels (0 = no tree) -> trees: drops labels without points or lower than
// min_tree_height, renumbers the rest 1.. in label order (rewriting tree_id), and measures top,
// base and point count. The base stands on the DTM at stem_xy[label - 1] (terrestrial) or, with
// stem_xy empty, below the top (airborne); stem_radius likewise, or 0.
std::vector<SegmentedTree> collect_trees(const PointCloud& cloud, const Terrain& terrain, std::vector<std::int32_t>& tree_id,
                                         std::size_t labels, const std::vector<Eigen::Vector2f>& stem_xy,
                                         const std::vector<float>& stem_radius, float min_tree_height);

}  // namespace treelobes
