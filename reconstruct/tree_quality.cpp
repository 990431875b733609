#include "reconstruct/tree_quality.hpp"

#include "geometry/ransac_fit.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace treelobes {

namespace {

// Robust (5th..95th percentile) extents of the inliers within their plane, along its axes.
struct PlaneBox {
    Eigen::Vector3f mean, a, b;  // the inliers' centre and the plane's in-plane axes
    Eigen::Vector2f low, high;   // 5th and 95th percentiles along a and b
    Eigen::Vector2f extent() const { return high - low; }
    bool holds(const Eigen::Vector3f& p) const {
        const Eigen::Vector2f q((p - mean).dot(a), (p - mean).dot(b));
        return (q.array() >= low.array()).all() && (q.array() <= high.array()).all();
    }
};

PlaneBox in_plane_box(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& inliers, const Eigen::Vector3f& normal) {
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
    PlaneBox box{mean, a, normal.cross(a), {}, {}};
    for (int k = 0; k < 2; ++k) {
        const Eigen::Vector3f& axis = k == 0 ? box.a : box.b;
        std::vector<float> v;
        for (int i : inliers) v.push_back((points[i] - mean).dot(axis));
        std::sort(v.begin(), v.end());
        box.low[k] = v[v.size() * 5 / 100];
        box.high[k] = v[v.size() * 95 / 100];
    }
    return box;
}

// A roof or a wall is a face with nothing just in front of it or behind it, out to about the
// spacing of its own points. Points that fill a volume are not: the returns of one airborne scan
// line through a sparse crown lie in a vertical plane 10-15 m wide (Megaplot, lidR's sample
// survey: 16 of a crown's 105 points, 3 m apart), with the neighbouring scan lines 0.5-1 m
// beside it. Counts the points between 3 band half-widths and that spacing (at least 5 half-
// widths) from the plane, within the inliers' box.
std::size_t points_beside(const std::vector<Eigen::Vector3f>& points, const PlaneFit& plane, const PlaneBox& box, float tolerance) {
    const Eigen::Vector2f extent = box.extent();
    const float spacing = std::sqrt(extent.x() * extent.y() / static_cast<float>(plane.inliers.size()));
    const float reach = std::max(5.0f * tolerance, spacing);
    std::size_t beside = 0;
    for (const Eigen::Vector3f& p : points) {
        const float d = std::abs(plane.signed_distance(p));
        if (d > 3.0f * tolerance && d <= reach && box.holds(p)) ++beside;
    }
    return beside;
}

// A face of a building: wide in both directions within the plane and nothing beside it.
bool is_face(const std::vector<Eigen::Vector3f>& whole_sample, const std::vector<Eigen::Vector3f>& sample, const PlaneFit& plane,
             const QualityOptions& o) {
    const PlaneBox box = in_plane_box(sample, plane.inliers, plane.normal);
    if (box.extent().minCoeff() < o.min_plane_extent) return false;
    const auto beside = static_cast<float>(points_beside(whole_sample, plane, box, o.plane_tolerance));
    return beside <= o.max_beside_ratio * static_cast<float>(plane.inliers.size());
}

// Area of the points' plan: the box of their 5th to 95th percentiles in x and y (at least 1 m^2).
float plan_area(const std::vector<Eigen::Vector3f>& points) {
    Eigen::Vector2f extent;
    for (int k = 0; k < 2; ++k) {
        std::vector<float> v;
        v.reserve(points.size());
        for (const Eigen::Vector3f& p : points) v.push_back(p[k]);
        std::sort(v.begin(), v.end());
        extent[k] = v[v.size() * 95 / 100] - v[v.size() * 5 / 100];
    }
    return std::max(1.0f, extent.x() * extent.y());
}

// A steep plane of an airborne scan sampled far more sparsely than its plan: one scan line
// through a crown (QualityOptions::airborne).
bool is_scan_line(const std::vector<Eigen::Vector3f>& sample, const PlaneFit& plane, float plan_density, const QualityOptions& o) {
    if (std::abs(plane.normal.z()) >= o.steep_plane_normal_z) return false;
    const Eigen::Vector2f extent = in_plane_box(sample, plane.inliers, plane.normal).extent();
    const float density = static_cast<float>(plane.inliers.size()) / std::max(1e-6f, extent.x() * extent.y());
    return density < o.min_wall_density * plan_density;
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
    const std::vector<Eigen::Vector3f> whole_sample = sample;  // the bands beside a plane count the points peeled off before
    std::size_t on_planes = 0;
    std::size_t on_scan_lines = 0;  // left out of the judgement (airborne)
    const float plan_density = static_cast<float>(total) / plan_area(sample);
    // Planes that are no face are peeled off too, so that up to twice max_planes are tried.
    for (int tried = 0; tried < 2 * o.max_planes && report.wide_planes < o.max_planes && sample.size() >= 50; ++tried) {
        const PlaneFit plane = fit_plane(sample, o.plane_tolerance, o.iterations);
        if (!plane.ok || plane.inliers.size() < total / 50) break;
        if (o.airborne && is_scan_line(sample, plane, plan_density, o)) {
            on_scan_lines += plane.inliers.size();
        } else if (is_face(whole_sample, sample, plane, o)) {
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
    // Fewer than 50 points off the scan lines cannot show a roof.
    const std::size_t judged = total - on_scan_lines;
    report.planar_fraction = judged < 50 ? 0.0f : static_cast<float>(on_planes) / static_cast<float>(judged);
    report.not_a_tree = report.planar_fraction > o.max_planar_fraction;
    if (report.not_a_tree) report.flags.push_back("not_a_tree");
    return report;
}

}  // namespace treelobes
