#include "forestry/measures.hpp"

#include "core/error.hpp"
#include "geometry/euclidean_clusters.hpp"
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

CircleFit fit_stem_circle(std::span<const Eigen::Vector2f> slice, const DbhOptions& options) {
    return fit_circle(slice, static_cast<float>(options.fit_tolerance), static_cast<float>(options.min_radius),
                      static_cast<float>(options.max_radius));
}

// Why a circle fitted to breast-height points is not a stem, or empty when it is one.
std::string stem_problem(const CircleFit& fit, std::span<const Eigen::Vector2f> slice, const DbhOptions& options) {
    if (fit.inliers < options.min_inliers) return "too few points on the fitted circle";
    if (fit.rms > options.max_relative_rms * fit.radius) return "the breast-height points do not lie on a circle";
    // A scanned stem is hollow: its points lie on the bark. Points filling the circle are
    // foliage or undergrowth, on which RANSAC also finds some circle.
    std::size_t interior = 0;
    for (const auto& p : slice) interior += (p - fit.centre).norm() < options.hollow_fraction * fit.radius;
    if (static_cast<double>(interior) > options.max_interior_share * static_cast<double>(fit.inliers))
        return "the breast-height points fill the circle (foliage or undergrowth, not a stem)";
    if (fit.coverage < options.min_coverage) return "the stem is seen over less than a quarter of its circumference";
    return {};
}

// The trunks at breast height, each a circle fitted to its own points: the slice's clusters,
// trunk_gap apart, that hold a circle passing every check of a stem. Clusters whose circles
// overlap are arcs of one trunk split by occlusion and are fitted together. A trunk much
// narrower than the widest (under 1 / 1.5 of its radius) is a limb or a sapling beside it, not
// a trunk of the same root collar, whose trunks are alike: two or more trunks left may be a
// multi-stemmed tree (a crape myrtle's, a coppiced tree's), whose trunks fitted all at once give
// a ring through them.
std::vector<CircleFit> separate_trunks(std::span<const Eigen::Vector2f> slice, const DbhOptions& options) {
    std::vector<Eigen::Vector3f> flat;
    for (const auto& p : slice) flat.emplace_back(p.x(), p.y(), 0.0f);
    struct Trunk {
        CircleFit circle;
        std::vector<Eigen::Vector2f> points;
    };
    std::vector<Trunk> arcs;
    for (const std::vector<int>& cluster : euclidean_clusters(flat, static_cast<float>(options.trunk_gap))) {
        if (cluster.size() < options.min_inliers) continue;
        Trunk arc;
        for (int i : cluster) arc.points.push_back(slice[static_cast<std::size_t>(i)]);
        arc.circle = fit_stem_circle(arc.points, options);
        if (arc.circle.ok && stem_problem(arc.circle, arc.points, options).empty()) arcs.push_back(std::move(arc));
    }
    std::stable_sort(arcs.begin(), arcs.end(), [](const Trunk& a, const Trunk& b) { return a.circle.inliers > b.circle.inliers; });
    std::vector<Trunk> trunks;
    for (Trunk& arc : arcs) {
        const auto same_trunk = std::find_if(trunks.begin(), trunks.end(), [&](const Trunk& t) {
            return (t.circle.centre - arc.circle.centre).norm() <= t.circle.radius + arc.circle.radius;
        });
        if (same_trunk == trunks.end())
            trunks.push_back(std::move(arc));
        else
            same_trunk->points.insert(same_trunk->points.end(), arc.points.begin(), arc.points.end());
    }
    std::vector<CircleFit> circles;
    for (const Trunk& trunk : trunks) {
        const CircleFit whole = fit_stem_circle(trunk.points, options);
        circles.push_back(whole.ok && stem_problem(whole, trunk.points, options).empty() ? whole : trunk.circle);
    }
    float widest = 0.0f;
    for (const CircleFit& circle : circles) widest = std::max(widest, circle.radius);
    std::erase_if(circles, [&](const CircleFit& circle) { return circle.radius < widest / 1.5f; });
    return circles;
}

// A trunk continues down from breast height toward the root collar; the hanging twigs of a
// willow's curtain, which can form circles of a trunk's size at breast height, end above the
// ground, and so do limbs and sprouts. Its points are looked for within `reach` of the circle's
// centre in the lower half of the way down to half the breast height, and for a trunk that may
// lean (a crape myrtle's trunks part from one collar at up to 30 degrees) in a cone that widens
// downward at `lean_degrees`.
bool reaches_down(const CircleFit& trunk, double reach, double lean_degrees, std::span<const Eigen::Vector3f> points,
                  std::span<const float> height_above_ground, const DbhOptions& options) {
    const double slope = std::tan(lean_degrees * std::numbers::pi / 180.0);
    const double top = options.breast_height - options.slice_half_width, bottom = 0.5 * options.breast_height;
    std::size_t low_points = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double hag = height_above_ground[i];
        if (hag < bottom || hag >= 0.5 * (top + bottom)) continue;
        low_points += (points[i].head<2>() - trunk.centre).norm() <= reach + (options.breast_height - hag) * slope;
    }
    return low_points >= options.min_inliers;
}

// The terrain at `centre` from the DTM heights under the points within `radius` of it (z - HAG):
// a least-squares plane through them, since a trunk seen from one side has all its points'
// ground on that side, up- or downhill of its centre; their median when they lie on a line.
std::optional<double> terrain_at(std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground,
                                 const Eigen::Vector2f& centre, float radius) {
    std::vector<Eigen::Vector3d> ground;  // relative to the centre, so the plane's constant term is its height there
    for (std::size_t i = 0; i < points.size(); ++i)
        if ((points[i].head<2>() - centre).norm() <= radius)
            ground.emplace_back(points[i].x() - centre.x(), points[i].y() - centre.y(), points[i].z() - height_above_ground[i]);
    if (ground.empty()) return std::nullopt;
    if (const std::optional<Eigen::Vector3d> plane = fit_height_plane_least_squares(ground)) return (*plane)(0);
    std::vector<double> heights;
    for (const Eigen::Vector3d& g : ground) heights.push_back(g.z());
    return quantile(heights, 0.5);
}

// Points at breast height above the terrain cut a trunk on a slope obliquely: on a 20-degree slope
// the cut spans 0.36 m of a 1 m trunk's height, and where the trunk tapers toward its root collar
// its points spread 8 cm across, so a circle through the outer ones fits (a flared mahogany of
// 1.027 m measured 1.257 m on a synthetic slope). The stem is cut again level, at breast height
// above the ground under it, within the first circle (and twice the fit tolerance beyond), as a
// forester's tape goes round it; that circle is kept when it holds as a stem.
CircleFit level_cut(const CircleFit& circle, std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground,
                    const DbhOptions& options) {
    const std::optional<double> ground = terrain_at(points, height_above_ground, circle.centre, circle.radius);
    if (!ground) return circle;
    const double height = *ground + options.breast_height;
    const float reach = circle.radius + 2.0f * static_cast<float>(options.fit_tolerance);
    std::vector<Eigen::Vector2f> level;
    for (const Eigen::Vector3f& p : points)
        if (std::abs(p.z() - height) <= options.slice_half_width && (p.head<2>() - circle.centre).norm() <= reach) level.push_back(p.head<2>());
    if (level.size() < options.min_inliers) return circle;
    const CircleFit cut = fit_stem_circle(level, options);
    return cut.ok && stem_problem(cut, level, options).empty() ? cut : circle;
}

// A multi-stemmed tree's trunks part from one collar and lean (a crape myrtle's at 12-24
// degrees), thin (5-6 cm) and carrying twigs from breast height up: a trunk smeared over the
// breast-height band with its twigs held circles of 0.10-0.14 m for trunks of 0.05-0.06 m. So
// each trunk is followed down from breast height in thin layers, each layer's circle looked for
// around the one above (its radius and 5 cm more: the lean moves it a few centimetres per
// layer), and its radius is the median of the layers' radii; below the twigs the layers agree
// (0.05-0.07 m between 0.7 and 1.1 m on the synthetic bench's crape myrtles). Fewer than three
// layers holding a circle leave the trunk as it was.
CircleFit follow_trunk_down(const CircleFit& trunk, std::span<const Eigen::Vector3f> points, std::span<const float> height_above_ground,
                            const DbhOptions& options) {
    CircleFit current = trunk;
    std::vector<float> radii;
    for (int k = 0; k < options.trunk_layers; ++k) {
        const double middle = options.breast_height - options.trunk_layer * k;
        const float reach = current.radius + 0.05f;
        std::vector<Eigen::Vector2f> layer;
        for (std::size_t i = 0; i < points.size(); ++i)
            if (std::abs(height_above_ground[i] - middle) <= 0.5 * options.trunk_layer && (points[i].head<2>() - current.centre).norm() <= reach)
                layer.push_back(points[i].head<2>());
        if (layer.size() < options.min_inliers) continue;
        const CircleFit circle = fit_stem_circle(layer, options);
        if (!circle.ok || !stem_problem(circle, layer, options).empty()) continue;
        radii.push_back(circle.radius);
        current = circle;
    }
    if (radii.size() < 3) return trunk;
    CircleFit followed = trunk;
    std::nth_element(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(radii.size() / 2), radii.end());
    followed.radius = radii[radii.size() / 2];
    return followed;
}

DbhMeasure multi_stem(DbhMeasure m, const std::vector<CircleFit>& trunks, const DbhOptions& options) {
    double squared_radii = 0.0;
    m.coverage = 1.0;
    m.centre.setZero();
    for (const CircleFit& trunk : trunks) {
        squared_radii += static_cast<double>(trunk.radius) * trunk.radius;
        m.centre += trunk.centre.cast<double>() / static_cast<double>(trunks.size());
        m.coverage = std::min(m.coverage, static_cast<double>(trunk.coverage));
        m.rms = std::max(m.rms, static_cast<double>(trunk.rms));
    }
    m.quality = m.coverage >= options.ok_coverage ? DbhQuality::Ok : DbhQuality::PartialArc;
    m.diameter = 2.0 * std::sqrt(squared_radii);
    m.stems = static_cast<int>(trunks.size());
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
    const std::vector<CircleFit> trunks = separate_trunks(slice, options);
    const bool multi_stemmed = trunks.size() >= 2 && std::all_of(trunks.begin(), trunks.end(), [&](const CircleFit& trunk) {
        return reaches_down(trunk, trunk.radius + options.fit_tolerance, options.max_trunk_lean, points, height_above_ground, options);
    });
    if (multi_stemmed) {
        std::vector<CircleFit> followed;
        for (const CircleFit& trunk : trunks) followed.push_back(follow_trunk_down(trunk, points, height_above_ground, options));
        return multi_stem(m, followed, options);
    }
    CircleFit fit = fit_stem_circle(slice, options);
    if (!fit.ok) return not_visible(m, "no circle fits the breast-height points");
    // A limb, a sprout or a bundle of twigs crossing breast height can hold more points than a
    // trunk seen from one side, and the circle is then theirs. When it does not reach down
    // (within 1.5 radii, a root flare) and the points it leaves hold a stem's circle that does,
    // that one is the stem.
    const auto stands_on_the_ground = [&](const CircleFit& circle) {
        return reaches_down(circle, 1.5 * circle.radius + 2.0 * options.fit_tolerance, 0.0, points, height_above_ground, options);
    };
    if (stem_problem(fit, slice, options).empty() && !stands_on_the_ground(fit)) {
        std::vector<Eigen::Vector2f> rest;
        for (const auto& p : slice)
            if ((p - fit.centre).norm() > fit.radius + 2.0f * static_cast<float>(options.fit_tolerance)) rest.push_back(p);
        const CircleFit other = rest.size() >= options.min_inliers ? fit_stem_circle(rest, options) : CircleFit{};
        if (other.ok && stem_problem(other, rest, options).empty() && stands_on_the_ground(other))
            fit = other;
    }
    const auto describe = [&m](const CircleFit& circle) {
        m.centre = circle.centre.cast<double>();
        m.coverage = circle.coverage;
        m.rms = circle.rms;
    };
    describe(fit);
    if (const std::string problem = stem_problem(fit, slice, options); !problem.empty()) return not_visible(m, problem);
    fit = level_cut(fit, points, height_above_ground, options);
    describe(fit);
    m.quality = fit.coverage >= options.ok_coverage ? DbhQuality::Ok : DbhQuality::PartialArc;
    m.diameter = 2.0 * fit.radius;
    m.stems = 1;
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

    m.outline = projected_hull(points);
    if (const double area = ring_area(m.outline); area > 0) {
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
