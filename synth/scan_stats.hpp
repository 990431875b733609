// Simple statistics that say whether a scan looks like a real one (used to compare simulated
// scans with real TLS and ALS data in tests and benchmarks).
#pragma once

#include "core/point_cloud.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace treelobes::synth {

// One point per cubic voxel of side `voxel` (the first in file order), as scans published
// "thinned to 1 cm" are (treels/pine.las: nearest neighbours exactly 1 cm apart). Simulated
// scans are thinned the same way before their density is compared with such files.
PointCloud voxel_thin(const PointCloud& cloud, double voxel);

// Share of the points in each of `bins` equal height slices, over the points of a square column
// (half width `half_width` around `centre`, global x y) from `min_height` above the column's base
// (its 0.5th percentile of z, robust to stray low points) to its top. Sums to 1.
std::vector<double> height_profile(const PointCloud& cloud, const Eigen::Vector2d& centre, double half_width, int bins,
                                   double min_height = 0.5);

// Sum of absolute differences of two profiles (0 = same shape, 2 = disjoint).
double profile_distance(const std::vector<double>& a, const std::vector<double>& b);

// A circle fitted to the stem slice [z_lo, z_hi] above the column base within `search` of
// `centre`: centre, radius, RMS of the radial residuals (points within 10 cm of the circle).
struct StemFit {
    Eigen::Vector2d centre{0, 0};
    double radius = 0;
    double rms = 0;
    std::size_t points = 0;
};
StemFit fit_stem(const PointCloud& cloud, const Eigen::Vector2d& centre, double search, double z_lo = 1.0, double z_hi = 1.6);

// Return-number mix: fraction of points with return number 1, 2, 3, 4+ and points per m^2 over
// the x-y bounding box.
struct ReturnMix {
    std::array<double, 4> by_return{0, 0, 0, 0};
    double points_per_m2 = 0;
    double first_returns_per_m2 = 0;
};
ReturnMix return_mix(const PointCloud& cloud);

}  // namespace treelobes::synth
