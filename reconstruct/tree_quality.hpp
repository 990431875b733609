// Is this scan a tree? Buildings, walls and cars are made of large flat faces; trees are not
// (even a thick stem only fits a narrow strip of a plane). The check peels up to a few RANSAC
// planes off a subsample and measures how much of the cloud lies on faces: planes that are wide
// in both in-plane directions with nothing just beside them (a sparse crown's returns fall into
// lucky planes too, but with more returns beside them). Skeleton statistics add softer flags.
#pragma once

#include <Eigen/Core>

#include <span>
#include <string>
#include <vector>

namespace treelobes {

struct QualityOptions {
    std::size_t sample_points = 3000;  // subsample used for the plane search
    int max_planes = 4;                // wide planes counted at most (twice as many are tried)
    int iterations = 150;               // RANSAC iterations per plane
    float plane_tolerance = 0.03f;      // metres: inlier band of a plane
    float min_plane_extent = 1.5f;      // metres: a plane counts when wider than this in both directions
    float max_planar_fraction = 0.35f;  // more of the cloud on wide planes than this: not a tree
    // A plane counts only when the bands beside it (assess_planarity) hold at most this many
    // points per point of its own band; points scattered through a volume give 2 or more.
    float max_beside_ratio = 0.5f;
    // An airborne scan's beams fall nearly vertically: they sample roofs as densely as the ground
    // plan, but walls sparsely, and a steep plane (normal less than steep_plane_normal_z up from
    // horizontal: within 15 degrees of vertical) among its returns is as often one scan line
    // through a crown, whose returns lie over the crown's depth, mostly at under 16 % of the
    // plan's density (Megaplot's crowns: median 9 %, 90th percentile 16 %; a house's walls
    // scanned from the street: 23-35 %). With
    // `airborne`, a steep plane sampled less densely than min_wall_density x the points per
    // square metre of the cloud's plan is such a line: its points are left out and the rest is
    // judged.
    bool airborne = false;
    float steep_plane_normal_z = 0.26f;
    float min_wall_density = 0.2f;
};

struct QualityReport {
    bool not_a_tree = false;
    float planar_fraction = 0.0f;    // fraction of the (judged) points on faces
    int wide_planes = 0;             // faces found (assess_planarity)
    std::vector<std::string> flags;  // "not_a_tree", "stem_not_visible", ...
};

// Planarity part of the check, on the cleaned points (ground already removed).
QualityReport assess_planarity(std::span<const Eigen::Vector3f> points, const QualityOptions& options = {});

}  // namespace treelobes
