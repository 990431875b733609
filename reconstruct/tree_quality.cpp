#include "reconstruct/tree_quality.hpp"

#include "geometry/ransac_fit.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>

namespace treelobes {

namespace {

// Robust (5th..95th percentile) extents of points within their plane.
Eigen::Vector2f in_plane_extent(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& inliers,
                                const Eigen::Vector3f& normal) {
    // In-plane axes from the principal direction of the inliers, so a long thin strip along a
    // stem is measured as long and thin, whatever its orientation.
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    for (int i : inliers) mean += points[i];
    mean /= static_cast<float>(inliers.size());
    Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
    for (int i : inliers) cov += (points[i] - mean) * (points[i] - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver(cov);
    Eigen::Vector3f a = solver.eigenvectors().col(2);
    a = (a - a.dot(normal) * normal).normalized();
    const Eigen::Vector3f b = normal.cross(a);
    Eigen::Vector2f extent;
    for (int k = 0; k < 2; ++k) {
        const Eigen::Vector3f axis = k == 0 ? a : b;
        std::vector<float> v;
        for (int i : inliers) v.push_back((points[i] - mean).dot(axis));
        std::sort(v.begin(), v.end());
        extent[k] = v[v.size() * 95 / 100] - v[v.size() * 5 / 100];
    }
    return extent;
}

}  // namespace

QualityReport assess_planarity(std::span<const Eigen::Vector3f> points, const QualityOptions& o) {
    QualityReport report;
    if (points.size() < 50) return report;
    // Evenly strided subsample: deterministic and spread over the whole cloud.
    std::vector<Eigen::Vector3f> sample;
    const std::size_t stride = std::max<std::size_t>(1, points.size() / o.sample_points);
    for (std::size_t i = 0; i < points.size(); i += stride) sample.push_back(points[i]);
    const std::size_t total = sample.size();
    std::size_t on_planes = 0;
    for (int k = 0; k < o.max_planes && sample.size() >= 50; ++k) {
        const PlaneFit plane = fit_plane(sample, o.plane_tolerance, o.iterations);
        if (!plane.ok || plane.inliers.size() < total / 50) break;
        const Eigen::Vector2f extent = in_plane_extent(sample, plane.inliers, plane.normal);
        if (extent.minCoeff() >= o.min_plane_extent) {
            on_planes += plane.inliers.size();
            ++report.wide_planes;
        }
        std::vector<bool> drop(sample.size(), false);
        for (int i : plane.inliers) drop[i] = true;
        std::vector<Eigen::Vector3f> rest;
        for (std::size_t i = 0; i < sample.size(); ++i)
            if (!drop[i]) rest.push_back(sample[i]);
        sample.swap(rest);
    }
    report.planar_fraction = static_cast<float>(on_planes) / static_cast<float>(total);
    report.not_a_tree = report.planar_fraction > o.max_planar_fraction;
    if (report.not_a_tree) report.flags.push_back("not_a_tree");
    return report;
}

}  // namespace treelobes
