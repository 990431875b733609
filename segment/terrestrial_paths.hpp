// Terrestrial tree segmentation: the stems of the slice, then one multi-source Dijkstra over the
// plot's neighbour graph from all of them (docs/segment.md, "Terrestrial", steps 2-5).
#pragma once

#include "core/point_cloud.hpp"
#include "segment/segment_trees.hpp"
#include "segment/terrain.hpp"

#include <cstdint>
#include <vector>

namespace treelobes {

// Labels the vegetation points by the stem whose paths reach them most cheaply
// (result.tree_id, zero-filled, one per point; 0 = no tree) and lists the trees.
void segment_terrestrial(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                         const SegmentOptions& options, TreeSegmentation& result);

}  // namespace treelobes
