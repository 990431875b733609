// Forestry measures of one segmented tree (docs/tile.md defines each: how it is measured, its
// unit and when it is not available). Inputs are the tree's points in the tile's local frame
// and each point's height above the terrain model (HAG), so sloped ground needs no special case.
// A measure that the scan cannot support is left empty (std::nullopt) or flagged, never guessed.
#pragma once

#include "core/tree_graph.hpp"

#include <Eigen/Core>

#include <optional>
#include <span>
#include <string>
#include <vector>

namespace treelobes::forestry {

// How a DBH was obtained: `Ok` a circle fitted to stem points seen around most of the stem,
// `PartialArc` a circle fitted to one side only (a number, less certain), `NotVisible` no stem
// at breast height in the scan (no number). A multi-stemmed tree's DBH is `Ok` when every
// trunk's circle is.
enum class DbhQuality { Ok, PartialArc, NotVisible };
const char* dbh_quality_name(DbhQuality quality);

struct DbhOptions {
    double breast_height = 1.3;                   // metres above the terrain
    double slice_half_width = 0.1;                // metres: points with |HAG - breast_height| below this
    double search_radius = 1.5;                   // metres around the stem base (horizontal)
    double fit_tolerance = 0.02;                  // metres: RANSAC inlier band of the circle
    double min_radius = 0.015, max_radius = 1.0;  // metres
    std::size_t min_inliers = 8;
    double ok_coverage = 0.6;          // fraction of 10-degree sectors around the centre holding inliers
    double min_coverage = 0.25;        // below: not_visible
    double max_relative_rms = 0.25;    // rms / radius above this: not a stem (branch clutter, leaves)
    double hollow_fraction = 0.6;      // points closer to the centre than this many radii are inside the stem...
    double max_interior_share = 0.25;  // ...and more of them than this share of the inliers: not a stem
    double trunk_gap = 0.1;            // metres: breast-height points this far apart belong to different trunks
    double max_trunk_lean = 30.0;      // degrees: how far a multi-stemmed tree's trunk may lean below breast height
    // A multi-stemmed tree's trunks are followed down from breast height in layers this thick ...
    double trunk_layer = 0.1;  // metres
    int trunk_layers = 7;      // ... this many (1.3 m down to 0.7 m)
};

struct DbhMeasure {
    DbhQuality quality = DbhQuality::NotVisible;
    // Metres; set for Ok and PartialArc. For a multi-stemmed tree the equivalent diameter, that
    // of the one stem of the same cross-section: sqrt(sum of the trunks' diameters squared).
    std::optional<double> diameter;
    int stems = 0;                 // trunks at breast height the diameter covers (0 when not visible)
    Eigen::Vector2d centre{0, 0};  // local frame, when a circle was fitted (a multi-stemmed tree: its trunks' mean)
    double coverage = 0.0;         // of the fitted circle (0 when none; the least of a multi-stemmed tree's)
    double rms = 0.0;              // metres (the largest of a multi-stemmed tree's)
    std::size_t slice_points = 0;  // points in the breast-height slice near the base
    std::string reason;            // why not_visible, or empty
};

// `base` is the stem base in the local frame (its x, y limit the search). Breast-height points
// that fall apart into two or more trunks, each holding a circle, alike in radius and not
// overlapping, are a multi-stemmed tree; otherwise one circle is fitted to all of them.
DbhMeasure measure_dbh(std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground, const Eigen::Vector3d& base,
                       const DbhOptions& options = {});

struct CrownOptions {
    double min_offset = 0.5;       // metres: crown points lie at least this far from the stem axis...
    double offset_fraction = 0.1;  // ...and this fraction of the tree's horizontal extent
    double base_quantile = 0.05;   // crown base = this quantile of the crown points' heights above the stem base
    std::size_t min_points = 10;
    double alpha_factor = 2.0;  // crown volume: alpha shape at alpha = factor * alpha_min
    double volume_cell = 0.25;  // metres: crown points thinned on this grid for the alpha shape
    std::size_t max_volume_points = 3000;
};

struct CrownMeasure {
    std::optional<double> base_height;     // metres above the ground at the stem (as the tree height)
    std::optional<double> diameter;        // metres: diameter of the circle with the projected area
    std::optional<double> projected_area;  // square metres: convex hull of the points seen from above
    // That hull's corners (local x, y; counter-clockwise, the first not repeated): the crown's
    // outline in crowns.geojson. Empty when there is no projected area.
    std::vector<Eigen::Vector2d> outline;
    std::optional<double> volume;          // cubic metres: alpha shape of the crown points
    std::string volume_failure;            // why there is no volume, or empty
};

// `base` is the stem position with z the ground there: heights within the crown are measured from
// it, as the tree's height is, not from the terrain under each point (on a slope that would move
// the crown base of a crown reaching downhill).
CrownMeasure measure_crown(std::span<const Eigen::Vector3f> points, const Eigen::Vector3d& base, const CrownOptions& options = {});

// The ground under `xy` as a tree's own points give it: the median of z - HAG (each point's
// height is taken from the DTM beneath it) over the points within `radius` horizontally;
// nullopt when none lies that close.
std::optional<double> ground_under(std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground,
                                   const Eigen::Vector2d& xy, double radius = 1.0);

// Volume of the skeleton's branches as truncated cones between each node and its parent
// (cubic metres), from the node radii.
double woody_volume(const TreeGraph& skeleton);

}  // namespace treelobes::forestry
