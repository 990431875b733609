// Robust plane and circle fits (PCL sample consensus, kept in ransac_fit.cpp). Used for ground
// planes, the "not a tree" check (large planar surfaces) and stem circles. Deterministic: PCL's
// samplers use a fixed seed.
#pragma once

#include <Eigen/Core>

#include <span>
#include <vector>

namespace treelobes {

struct PlaneFit {
    bool ok = false;
    Eigen::Vector3f normal{0, 0, 1};  // unit, oriented so that normal.z >= 0
    float offset = 0.0f;              // plane: normal . p + offset = 0
    std::vector<int> inliers;         // indices into the input
    float signed_distance(const Eigen::Vector3f& p) const { return normal.dot(p) + offset; }
};

// RANSAC plane with inlier band `threshold` (metres). ok = false with fewer than 3 points or no model.
// max_tilt_degrees > 0 only accepts planes whose normal is within that angle of the z axis
// (ground: a dense stem face must not win).
PlaneFit fit_plane(std::span<const Eigen::Vector3f> points, float threshold, int max_iterations = 1000,
                   float max_tilt_degrees = 0.0f);

struct CircleFit {
    bool ok = false;
    Eigen::Vector2f centre{0, 0};
    float radius = 0.0f;
    float rms = 0.0f;            // RMS of |distance to centre - radius| over the inliers (metres)
    std::size_t inliers = 0;
    float coverage = 0.0f;       // fraction of 10-degree sectors around the centre holding inliers
};

// RANSAC circle (radius limited to [min_radius, max_radius]) refined by geometric least
// squares on its inliers. ok = false with fewer than 5 points or when no circle fits.
CircleFit fit_circle(std::span<const Eigen::Vector2f> points, float threshold, float min_radius, float max_radius,
                     int max_iterations = 500);

}  // namespace treelobes
