#include "forestry/measures.hpp"

#include "core/error.hpp"
#include "geometry/grid_thinning.hpp"
#include "geometry/ransac_fit.hpp"
#include "geometry/alpha_shape.hpp"
#include "geometry/convex_hull.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace treelobes::forestry {

const char* dbh_quality_name(DbhQuality quality) {
    switch (quality) {
        case DbhQuality::Ok:
            return "ok";
        case DbhQuality::PartialArc:
            return "partial_arc";
        case DbhQuality::NotVisible:
            return "not_visible";
    }
    throw Error(ExitCode::Internal, "unknown DBH quality");
}

namespace {

void check_sizes(std::span<const Eigen::Vector3f> points, std::span<const float> hag, const char* what) {
    if (points.size() != hag.size()) throw Error(ExitCode::Internal, std::string(what) + ": one height above ground per point expected");
}

double horizontal_distance(const Eigen::Vector3f& p, const Eigen::Vector3d& base) { return std::hypot(p.x() - base.x(), p.y() - base.y()); }

// Value at quantile q (0..1) of `values` (nearest rank); values must not be empty.
double quantile(std::vector<double> values, double q) {
    const auto k = static_cast<std::size_t>(std::llround(q * static_cast<double>(values.size() - 1)));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
}

DbhMeasure not_visible(DbhMeasure m, std::string reason) {
    m.quality = DbhQuality::NotVisible;
    m.diameter.reset();
    m.reason = std::move(reason);
    return m;
}

}  // namespace

DbhMeasure measure_dbh(std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground, const Eigen::Vector3d& base,
                       const DbhOptions& options) {
    check_sizes(points, height_above_ground, "measure_dbh");
    std::vector<Eigen::Vector2f> slice;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (std::abs(height_above_ground[i] - options.breast_height) <= options.slice_half_width &&
            horizontal_distance(points[i], base) <= options.search_radius)
            slice.emplace_back(points[i].x(), points[i].y());
    DbhMeasure m;
    m.slice_points = slice.size();
    if (slice.size() < options.min_inliers)
        return not_visible(m, "fewer than " + std::to_string(options.min_inliers) + " points at breast height");
    const CircleFit fit = fit_circle(slice, static_cast<float>(options.fit_tolerance), static_cast<float>(options.min_radius),
                                     static_cast<float>(options.max_radius));
    if (!fit.ok) return not_visible(m, "no circle fits the breast-height points");
    m.centre = fit.centre.cast<double>();
    m.coverage = fit.coverage;
    m.rms = fit.rms;
    if (fit.inliers < options.min_inliers) return not_visible(m, "too few points on the fitted circle");
    if (fit.rms > options.max_relative_rms * fit.radius) return not_visible(m, "the breast-height points do not lie on a circle");
    // A scanned stem is hollow: its points lie on the bark. Points filling the circle are
    // foliage or undergrowth, on which RANSAC also finds some circle.
    std::size_t interior = 0;
    for (const auto& p : slice) interior += (p - fit.centre).norm() < options.hollow_fraction * fit.radius;
    if (static_cast<double>(interior) > options.max_interior_share * static_cast<double>(fit.inliers))
        return not_visible(m, "the breast-height points fill the circle (foliage or undergrowth, not a stem)");
    if (fit.coverage < options.min_coverage) return not_visible(m, "the stem is seen over less than a quarter of its circumference");
    m.quality = fit.coverage >= options.ok_coverage ? DbhQuality::Ok : DbhQuality::PartialArc;
    m.diameter = 2.0 * fit.radius;
    return m;
}

CrownMeasure measure_crown(std::span<const Eigen::Vector3f> points, const Eigen::Vector3d& base, const CrownOptions& options) {
    CrownMeasure m;
    if (points.size() < options.min_points) {
        m.volume_failure = "too few points";
        return m;
    }
    double reach = 0;  // horizontal extent of the tree from its stem axis
    for (const auto& p : points) reach = std::max(reach, horizontal_distance(p, base));
    const double offset = std::max(options.min_offset, options.offset_fraction * reach);
    std::vector<double> crown_heights;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (horizontal_distance(points[i], base) >= offset) crown_heights.push_back(points[i].z() - base.z());
    if (crown_heights.size() >= options.min_points) m.base_height = std::max(0.0, quantile(crown_heights, options.base_quantile));

    const double area = projected_hull_area(points);
    if (area > 0) {
        m.projected_area = area;
        m.diameter = equal_area_diameter(area);
    }

    std::vector<Eigen::Vector3f> crown;
    const double floor = base.z() + m.base_height.value_or(0.0);
    for (const Eigen::Vector3f& p : points)
        if (p.z() >= floor) crown.push_back(p);
    double cell = options.volume_cell;
    std::vector<std::size_t> kept = first_point_per_cell(crown, static_cast<float>(cell));
    while (kept.size() > options.max_volume_points) {  // coarser cells until the alpha shape stays affordable
        cell *= 1.25;
        kept = first_point_per_cell(crown, static_cast<float>(cell));
    }
    std::vector<Eigen::Vector3f> thinned;
    thinned.reserve(kept.size());
    for (std::size_t i : kept) thinned.push_back(crown[i]);
    if (thinned.size() < 4) {
        m.volume_failure = "fewer than 4 crown points";
        return m;
    }
    const AlphaShapeResult shape = alpha_shape(thinned, {.alpha_factor = options.alpha_factor});
    if (!shape.failure.empty())
        m.volume_failure = shape.failure;
    else
        m.volume = std::abs(shape.mesh.signed_volume());
    return m;
}

std::optional<double> ground_under(std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground,
                                   const Eigen::Vector2d& xy, double radius) {
    std::vector<double> ground;
    for (std::size_t i = 0; i < points.size(); ++i)
        if ((points[i].head<2>().cast<double>() - xy).norm() <= radius)
            ground.push_back(static_cast<double>(points[i].z() - height_above_ground[i]));
    if (ground.empty()) return std::nullopt;
    const auto mid = ground.begin() + static_cast<std::ptrdiff_t>(ground.size() / 2);
    std::nth_element(ground.begin(), mid, ground.end());
    return *mid;
}

double woody_volume(const TreeGraph& skeleton) {
    double volume = 0;
    for (std::size_t i = 1; i < skeleton.size(); ++i) {
        const TreeNode& node = skeleton.nodes[i];
        const double r1 = node.radius, r2 = skeleton.nodes[node.parent].radius;
        const double h = skeleton.edge_length(static_cast<int>(i));
        volume += std::numbers::pi / 3.0 * h * (r1 * r1 + r1 * r2 + r2 * r2);
    }
    return volume;
}

}  // namespace treelobes::forestry
