// Robust plane and circle fits (PCL sample consensus, kept in ransac_fit.cpp). Used for ground
// planes, the "not a tree" check (large planar surfaces) and stem circles. Deterministic: PCL's
// samplers use a fixed seed. Also the closed-form least-squares circle that cheap stem
// estimates use (classification's DBH feature, the scan statistics of synthetic trees), and a
// least-squares height plane (the ground under a stem, forestry's DBH).
#pragma once

#include <Eigen/Core>

#include <optional>
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
PlaneFit fit_plane(std::span<const Eigen::Vector3f> points, float threshold, int max_iterations = 1000, float max_tilt_degrees = 0.0f);

struct CircleFit {
    bool ok = false;
    Eigen::Vector2f centre{0, 0};
    float radius = 0.0f;
    float rms = 0.0f;  // RMS of |distance to centre - radius| over the inliers (metres)
    std::size_t inliers = 0;
    float coverage = 0.0f;  // fraction of 10-degree sectors around the centre holding inliers
};

// RANSAC circle (radius limited to [min_radius, max_radius]) refined by geometric least
// squares on its inliers. ok = false with fewer than 5 points or when no circle fits.
CircleFit fit_circle(std::span<const Eigen::Vector2f> points, float threshold, float min_radius, float max_radius,
                     int max_iterations = 500);

struct Circle2d {
    Eigen::Vector2d centre{0, 0};
    double radius = 0;
};

// Kasa's algebraic least-squares circle x^2 + y^2 + D x + E y + F = 0 through all points: one
// linear solve, no outlier rejection, so only for slices known to be mostly stem. nullopt with
// fewer than 3 points, coincident or collinear points, or when the points admit no real circle.
std::optional<Circle2d> fit_circle_least_squares(std::span<const Eigen::Vector2d> points);

// Least-squares height plane z = a + b x + c y through all points (no outlier rejection: for
// smooth surfaces such as DTM heights), as (a, b, c). nullopt with fewer than 3 points or when
// their (x, y) are coincident or collinear.
std::optional<Eigen::Vector3d> fit_height_plane_least_squares(std::span<const Eigen::Vector3d> points);

}  // namespace treelobes
