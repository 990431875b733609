// Airborne tree segmentation: a pit-free canopy height model, treetops in windows that widen
// with height, shallow tops merged into higher ones, crowns grown from the tops (docs/segment.md,
// "Airborne").
#pragma once

#include "core/point_cloud.hpp"
#include "segment/segment_trees.hpp"
#include "segment/terrain.hpp"

#include <cstdint>
#include <vector>

namespace treelobes {

// Mean spacing of the vegetation returns seen from above, 1 / sqrt(returns per m^2 over the 2 m
// cells that hold any); 0 without vegetation.
float return_spacing_of(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation);

// Labels the vegetation points by crown (result.tree_id, zero-filled, one per point) and lists
// the trees; records the return spacing and the CHM grid used in `result`.
void segment_airborne(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                      const SegmentOptions& requested, TreeSegmentation& result);

}  // namespace treelobes
