// Agreement of a tree segmentation with per-point reference labels (synthetic truth or another
// tool's segmentation, e.g. lidR's treeID). A reference tree and a found tree match when each
// holds at least half of the other's points, so each tree has at most one match.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes {

struct HeightClassCounts {
    std::string name;  // "5-10 m", "10-20 m", "20+ m"
    std::size_t reference = 0, found = 0, matched = 0;
};

struct SegmentationScore {
    std::size_t reference_trees = 0;  // reference trees taller than min_height
    std::size_t found_trees = 0;      // found trees taller than min_height
    std::size_t matched = 0;          // matched pairs whose reference tree is counted
    double precision = 0, recall = 0, f1 = 0;
    // Share of the counted reference trees' points whose found id is the one matched to their tree.
    double points_right = 0;
    std::vector<HeightClassCounts> by_height;  // the matching table
};

// `reference` and `found`: one id per point, 0 = no tree. A tree's height is the largest
// `height_above_ground` of its points; only trees taller than `min_height` are counted (a match
// of a counted reference tree with a found tree of any height is a match; found trees matched to
// shorter reference trees are not counted as false). Throws Error(Internal) when sizes differ.
SegmentationScore score_segmentation(std::span<const std::int32_t> reference, std::span<const std::int32_t> found,
                                     std::span<const float> height_above_ground, float min_height);

}  // namespace treelobes
