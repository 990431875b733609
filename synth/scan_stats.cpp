#include "synth/scan_stats.hpp"

#include "core/error.hpp"
#include "geometry/grid_thinning.hpp"
#include "geometry/ransac_fit.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace treelobes::synth {

namespace {

std::vector<std::size_t> column(const PointCloud& cloud, const Eigen::Vector2d& centre, double half_width) {
    std::vector<std::size_t> inside;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud.global(i);
        if (std::abs(p.x() - centre.x()) <= half_width && std::abs(p.y() - centre.y()) <= half_width) inside.push_back(i);
    }
    if (inside.empty()) throw Error::usage("no points in the column around the stem");
    return inside;
}

double base_of(const PointCloud& cloud, const std::vector<std::size_t>& idx) {
    std::vector<double> z;
    z.reserve(idx.size());
    for (auto i : idx) z.push_back(cloud.global(i).z());
    const std::size_t k = z.size() / 200;
    std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(k), z.end());
    return z[k];
}

}  // namespace

PointCloud voxel_thin(const PointCloud& cloud, double voxel) {
    if (!(voxel > 0)) throw Error::usage("voxel size must be positive");
    std::vector<Eigen::Vector3d> global(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) global[i] = cloud.global(i);
    const std::vector<std::size_t> keep = first_point_per_cell(global, voxel);
    return cloud.subset(keep);
}

std::vector<double> height_profile(const PointCloud& cloud, const Eigen::Vector2d& centre, double half_width, int bins, double min_height) {
    const auto idx = column(cloud, centre, half_width);
    const double base = base_of(cloud, idx);
    double top = base;
    for (auto i : idx) top = std::max(top, cloud.global(i).z());
    std::vector<double> profile(static_cast<std::size_t>(bins), 0.0);
    const double lo = base + min_height, span = top - lo;
    if (!(span > 0)) throw Error::usage("the column is lower than the minimum height");
    double total = 0;
    for (auto i : idx) {
        const double z = cloud.global(i).z();
        if (z < lo) continue;
        const int b = std::min(bins - 1, static_cast<int>((z - lo) / span * bins));
        profile[static_cast<std::size_t>(b)] += 1;
        total += 1;
    }
    for (auto& p : profile) p /= total;
    return profile;
}

double profile_distance(const std::vector<double>& a, const std::vector<double>& b) {
    double d = 0;
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) d += std::abs(a[i] - b[i]);
    return d;
}

StemFit fit_stem(const PointCloud& cloud, const Eigen::Vector2d& centre, double search, double z_lo, double z_hi) {
    const auto idx = column(cloud, centre, search);
    const double base = base_of(cloud, idx);
    std::vector<Eigen::Vector2d> slice;
    for (auto i : idx) {
        const Eigen::Vector3d p = cloud.global(i);
        if (p.z() >= base + z_lo && p.z() < base + z_hi) slice.push_back(p.head<2>());
    }
    StemFit fit;
    const std::optional<Circle2d> first = fit_circle_least_squares(slice);
    if (!first) throw Error::usage("cannot fit a stem circle: too few points in the slice");
    // Refit on the points near the first circle: branches and leaves in the slice are not stem.
    std::vector<Eigen::Vector2d> near;
    for (const auto& p : slice)
        if (std::abs((p - first->centre).norm() - first->radius) < 0.1) near.push_back(p);
    const std::optional<Circle2d> refit = fit_circle_least_squares(near);
    if (!refit) throw Error::usage("cannot fit a stem circle");
    const Eigen::Vector2d c = refit->centre;
    const double r = refit->radius;
    double sum2 = 0;
    std::size_t n = 0;
    for (const auto& p : near) {
        const double e = (p - c).norm() - r;
        if (std::abs(e) >= 0.1) continue;
        sum2 += e * e;
        ++n;
    }
    fit.centre = c;
    fit.radius = r;
    fit.points = n;
    fit.rms = n ? std::sqrt(sum2 / static_cast<double>(n)) : 0.0;
    return fit;
}

ReturnMix return_mix(const PointCloud& cloud) {
    ReturnMix mix;
    if (cloud.empty()) return mix;
    const auto [lo, hi] = cloud.bounds();
    const double area = std::max(1e-9, static_cast<double>(hi.x() - lo.x()) * static_cast<double>(hi.y() - lo.y()));
    std::size_t first = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const int r = cloud.return_number.empty() ? 1 : std::max<int>(1, cloud.return_number[i]);
        mix.by_return[static_cast<std::size_t>(std::min(r, 4) - 1)] += 1;
        first += r == 1;
    }
    for (auto& f : mix.by_return) f /= static_cast<double>(cloud.size());
    mix.points_per_m2 = static_cast<double>(cloud.size()) / area;
    mix.first_returns_per_m2 = static_cast<double>(first) / area;
    return mix;
}

}  // namespace treelobes::synth
