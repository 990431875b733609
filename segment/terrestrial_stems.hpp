// Terrestrial stems: clusters of the points in a slice above the DTM that fit upright circles,
// whole or layer by layer (docs/segment.md, "Terrestrial", step 1).
#pragma once

#include "core/point_cloud.hpp"
#include "segment/segment_trees.hpp"
#include "segment/terrain.hpp"

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace treelobes {

// One tree's stem as the slice shows it: the circle (or the equivalent circle of a multi-stemmed
// tree's trunks) and the slice points that seed the tree's paths.
struct Stem {
    Eigen::Vector2f centre;   // local frame
    float radius = 0;         // metres
    std::size_t inliers = 0;  // slice points on the circle
    std::vector<int> points;  // indices into the cloud: the stem's slice points
};

// Stems found in the slice that also have points under them down to the ground clearance, one
// per tree: arcs of one trunk split by occlusion give circles whose centres lie within each
// other, the one with more inliers stays; trunks closer than stem_merge_distance are one tree's,
// seeded from all of them and measured by the one with more inliers.
std::vector<Stem> find_stems(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                             const SegmentOptions& options);

}  // namespace treelobes
