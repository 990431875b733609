// Is this scan a tree? Buildings, walls and cars are made of large flat faces; trees are not
// (even a thick stem only fits a narrow strip of a plane). The check peels up to a few RANSAC
// planes off a subsample and measures how much of the cloud lies on planes that are wide in
// both in-plane directions. Skeleton statistics add softer flags.
#pragma once

#include <Eigen/Core>

#include <span>
#include <string>
#include <vector>

namespace treelobes {

struct QualityOptions {
    std::size_t sample_points = 3000;  // subsample used for the plane search
    int max_planes = 4;
    int iterations = 150;               // RANSAC iterations per plane
    float plane_tolerance = 0.03f;      // metres: inlier band of a plane
    float min_plane_extent = 1.5f;      // metres: a plane counts when wider than this in both directions
    float max_planar_fraction = 0.35f;  // more of the cloud on wide planes than this: not a tree
};

struct QualityReport {
    bool not_a_tree = false;
    float planar_fraction = 0.0f;  // fraction of the points on wide planes
    int wide_planes = 0;
    std::vector<std::string> flags;  // "not_a_tree", "stem_not_visible", ...
};

// Planarity part of the check, on the cleaned points (ground already removed).
QualityReport assess_planarity(std::span<const Eigen::Vector3f> points, const QualityOptions& options = {});

}  // namespace treelobes
