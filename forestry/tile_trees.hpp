// From a labelled tile to per-tree inputs, and the per-tree table that `treelobes tile` writes
// (trees.csv, trees.geojson, crowns.geojson, and one JSON record per tree that lets a re-run skip it).
#pragma once

#include "forestry/tree_pipeline.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace treelobes::forestry {

// Stem base of a tree (local frame) from its points and their heights above ground, for trees
// whose segmentation gave none (an input treeID): when the scan reaches down to the stem (the
// lowest point within `stem_reach` m of the ground), the median x, y of the points of the lowest
// metre; otherwise (a crown seen from above) the x, y of the highest point. z is the terrain
// there: the median of z - HAG of the points within 1 m horizontally (of all points when none).
Eigen::Vector3d estimate_stem_base(std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground,
                                   float stem_reach = 2.0f);

// One TreeInput per tree id > 0, ids ascending, each with the positions (no other attributes)
// and heights of its points. Trees in `bases` take that base (found at the stem when
// `bases_at_stems`, a terrestrial segmentation; placed under the treetop otherwise), others
// estimate_stem_base, which is not taken as found at the stem: the lowest points of an airborne
// scan are as often the crown's lowest twigs (the tree's measures then place the stem by the
// DBH circle or the crown's centre). Throws Error(Internal) for mismatched sizes.
std::vector<TreeInput> split_trees(const PointCloud& cloud, std::span<const std::int32_t> tree_id,
                                   std::span<const float> height_above_ground, const std::map<int, Eigen::Vector3d>& bases,
                                   bool bases_at_stems);

// A finished tree as the tables show it.
struct TreeRow {
    TreeMeasures measures;
    std::string species;                       // voted species; empty without a model
    std::optional<double> species_confidence;  // the tree's own probability of that species
    std::size_t lobes = 0;
    bool modelled = true;   // false: measured only, too few points for a model (no lobes, no woody volume, no files)
    std::string global_id;  // the tree's id across a survey (from its stem base; set by the caller)
};

// trees.csv: header then one row per tree (global_id first, then the tile's tree_id); global coordinates (origin added) to the millimetre;
// measures that are not available are empty cells. docs/tile.md lists the columns.
std::string trees_csv(const std::vector<TreeRow>& rows, const Eigen::Vector3d& origin);
// trees.geojson: a FeatureCollection of points (x, y, z in the tile's CRS) with the csv's values
// as properties (null when not available); the tile's CRS as WKT in a "crs_wkt" member when known.
std::string trees_geojson(const std::vector<TreeRow>& rows, const Eigen::Vector3d& origin, const std::string& crs_wkt);
// crowns.geojson: the same features with each crown's outline as their geometry, a polygon (the
// convex hull of the tree's points seen from above, whose area is crown_area_m2; x, y in the
// tile's CRS); null geometry for a tree without one (fewer than 3 points, or all on a line).
std::string crowns_geojson(const std::vector<TreeRow>& rows, const Eigen::Vector3d& origin, const std::string& crs_wkt);

// The revision of the per-tree measures and records: part of the key a re-run checks before it
// keeps a finished tree, and raised whenever a measure's definition changes, so that a tree
// measured by an older treelobes is measured again (3: stem position and height at the stem,
// measured-only trees; 4: crown base above the ground at the stem; 5: the DBH of multi-stemmed
// trees and the stem count; 6: the DBH circle cut level, not along the terrain, and a
// multi-stemmed tree's trunks followed down below their twigs; 7: a crown seen from above placed
// at the centre of its points without their outer fifth, and whether a modelled tree looks like a
// building, not_a_tree; 8: not_a_tree judged by faces, without an airborne crown's scan lines;
// 9: the crown's outline kept for crowns.geojson).
inline constexpr int kTreeRecordRevision = 9;

// The record of one finished tree (trees/tree_<id>.json): its row in full precision plus the
// options key it was made with. read_tree_record returns nullopt when the text is not such a
// record or was made with another key (the tree is then processed again).
std::string tree_record(const TreeRow& row, const Eigen::Vector3d& origin, const std::string& options_key);
std::optional<TreeRow> read_tree_record(const std::string& text, const std::string& options_key);

}  // namespace treelobes::forestry
