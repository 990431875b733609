#include "segment/terrestrial_stems.hpp"

#include "geometry/euclidean_clusters.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/ransac_fit.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <span>

namespace treelobes {

namespace {

// Euclidean clusters of the slice points (single linkage at `distance`), each as cloud indices.
std::vector<std::vector<int>> cluster_slice(const PointCloud& cloud, const std::vector<int>& slice, float distance) {
    std::vector<Eigen::Vector3f> points;
    points.reserve(slice.size());
    for (int i : slice) points.push_back(cloud.positions[static_cast<std::size_t>(i)]);
    std::vector<std::vector<int>> clusters = euclidean_clusters(points, distance);
    for (auto& cluster : clusters)
        for (int& member : cluster) member = slice[static_cast<std::size_t>(member)];
    return clusters;
}

// A stem stands upright: the centroids of the lower and upper halves of its samples (its slice
// points on the circle, or the centres of its layers' circles) lie above each other within
// `max_lean_degrees`. A low branch crossing the slice aslant can fit a circle arc too, but its
// halves are offset by its horizontal run.
bool upright(std::span<const Eigen::Vector3f> samples, float max_lean_degrees) {
    float low = std::numeric_limits<float>::infinity(), high = -low;
    for (const Eigen::Vector3f& p : samples) {
        low = std::min(low, p.z());
        high = std::max(high, p.z());
    }
    const float middle = 0.5f * (low + high);
    Eigen::Vector3d sum[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    std::size_t count[2] = {0, 0};
    for (const Eigen::Vector3f& p : samples) {
        const int half = p.z() >= middle;
        sum[half] += p.cast<double>();
        ++count[half];
    }
    if (!count[0] || !count[1]) return false;
    const Eigen::Vector3d step = sum[1] / count[1] - sum[0] / count[0];
    const double tangent = std::tan(static_cast<double>(max_lean_degrees) * std::numbers::pi / 180.0);
    return step.z() > 0 && step.head<2>().norm() <= tangent * step.z();
}

// A trunk holds its arc through the slice's whole height. A limb that droops across the slice
// does not: its band of points fits a wide arc that only some heights fill. Such a limb of a fig
// passed for a 0.77 m stem on a crowded plot and took 13 % of its tree points (docs/segment.md).
// The lowest quarter is not judged, since a root flare widens there. `samples` are the circle's
// points as (x, y, height above the DTM).
bool arc_in_every_upper_quarter(std::span<const Eigen::Vector3f> samples, const Eigen::Vector2f& centre, const SegmentOptions& options) {
    if (options.min_quarter_arc_share <= 0.0f) return true;
    constexpr int kSectors = 36;
    std::uint64_t all = 0, quarter[4] = {0, 0, 0, 0};
    const float span = options.stem_slice_high - options.stem_slice_low;
    for (const Eigen::Vector3f& p : samples) {
        const Eigen::Vector2f d = p.head<2>() - centre;
        const float turn = (std::atan2(d.y(), d.x()) + std::numbers::pi_v<float>) / (2.0f * std::numbers::pi_v<float>);
        const int sector = std::clamp(static_cast<int>(turn * kSectors), 0, kSectors - 1);
        const int q = std::clamp(static_cast<int>((p.z() - options.stem_slice_low) / span * 4.0f), 0, 3);
        all |= std::uint64_t{1} << sector;
        quarter[q] |= std::uint64_t{1} << sector;
    }
    const float needed = options.min_quarter_arc_share * static_cast<float>(std::popcount(all));
    for (int q = 1; q < 4; ++q)
        if (static_cast<float>(std::popcount(quarter[q])) < needed) return false;
    return true;
}

// The points as (x, y, height above the DTM). The slice is cut by height above the DTM, so on a
// slope its uphill side lies higher than its downhill side: split by z, the halves of a thick
// trunk would be its downhill and uphill arcs, offset by its diameter however upright it stands.
std::vector<Eigen::Vector3f> above_ground(const PointCloud& cloud, const std::vector<float>& height_above_ground,
                                          const std::vector<int>& points) {
    std::vector<Eigen::Vector3f> samples;
    samples.reserve(points.size());
    for (int i : points) {
        const auto k = static_cast<std::size_t>(i);
        samples.emplace_back(cloud.positions[k].x(), cloud.positions[k].y(), height_above_ground[k]);
    }
    return samples;
}

// Does a circle of a plausible radius hold enough of these points around enough of its
// circumference (Liang et al. 2012, §2.2)?
bool circle_holds(const CircleFit& circle, std::size_t points, const SegmentOptions& options) {
    return circle.ok && static_cast<float>(circle.inliers) >= options.min_circle_inliers * static_cast<float>(points) &&
           circle.coverage >= options.min_arc_coverage;
}

// A layer below a thick trunk's circles that holds no trunk circle may be its root flare: a
// wider circle on the same axis, up to the buttresses' reach. Buttresses are not round, so the
// circle holds only some of the layer's points, at least half the share a trunk's circle must
// hold (the synthetic figs of 1.3-1.7 m DBH: circles of 0.95-1.35 m round trunks of 0.63-0.75 m,
// through 25-55 % of the points, 1.0-1.75 m above the ground), around as much of its
// circumference as a trunk's, and its centre lies within half the trunk's radius of the axis.
bool is_flare_of(const std::vector<Eigen::Vector2f>& layer, const Stem& stem, const SegmentOptions& options) {
    if (static_cast<int>(layer.size()) < options.min_stem_points) return false;
    const CircleFit flare = fit_circle(layer, options.circle_tolerance, stem.radius, options.buttressed_foot_reach * stem.radius);
    return flare.ok && static_cast<float>(flare.inliers) >= 0.5f * options.min_circle_inliers * static_cast<float>(layer.size()) &&
           flare.coverage >= options.min_arc_coverage && (flare.centre - stem.centre).norm() <= 0.5f * stem.radius;
}

// A trunk that tapers within the slice (a root flare: the synthetic oaks, figs and mahoganies of
// 1.0-1.5 m narrow by a third between 1 and 2 m above the ground) holds no single circle over the
// slice's height, but each thin horizontal layer of it does. The stem is then the median of the
// layers' circles when at least half of the layers (two at least) hold one, or, under a thick
// trunk, hold one or its flare (`is_flare_of`: a flare can fill most of the slice), every layer's
// centre lies within half that radius of the median centre and every layer's radius within a
// factor 2 of it: one trunk, layer above layer, not a limb and a twig curtain that happen to
// fit circles at different places, nor a clump of twigs that fits a 7 cm circle in one layer and
// a 26 cm one above it (a fig's low crown, 8.9 m from its trunk, passed for a stem on an open
// plot that way: docs/segment.md). Whether it stands
// upright is judged by the circles' centres: the layers of a thick trunk see different arcs
// (occlusion changes with height), so their points' centroids wander by up to a radius.
std::optional<Stem> fit_stem_by_layers(const PointCloud& cloud, const std::vector<int>& cluster, float low, float high,
                                       const SegmentOptions& options) {
    const int count = std::max(1, static_cast<int>(std::ceil((high - low) / options.stem_layer_height)));
    std::vector<std::vector<Eigen::Vector2f>> layers(static_cast<std::size_t>(count));
    std::vector<std::vector<int>> layer_points(static_cast<std::size_t>(count));
    for (int i : cluster) {
        const Eigen::Vector3f& p = cloud.positions[static_cast<std::size_t>(i)];
        const auto k = static_cast<std::size_t>(std::min(count - 1, static_cast<int>((p.z() - low) / options.stem_layer_height)));
        layers[k].push_back(p.head<2>());
        layer_points[k].push_back(i);
    }
    std::vector<CircleFit> circles;
    std::vector<Eigen::Vector3f> centres;  // of the circles, at their layers' mid-heights
    std::vector<int> on_circles;
    int lowest_holding = count;
    for (int k = 0; k < count; ++k) {
        const std::vector<Eigen::Vector2f>& xy = layers[static_cast<std::size_t>(k)];
        if (static_cast<int>(xy.size()) < options.min_stem_points) continue;
        const CircleFit circle = fit_circle(xy, options.circle_tolerance, options.min_stem_radius, options.max_stem_radius);
        if (!circle_holds(circle, xy.size(), options)) continue;
        lowest_holding = std::min(lowest_holding, k);
        circles.push_back(circle);
        centres.emplace_back(circle.centre.x(), circle.centre.y(), low + (static_cast<float>(k) + 0.5f) * options.stem_layer_height);
        for (std::size_t j = 0; j < xy.size(); ++j)
            if (std::abs((xy[j] - circle.centre).norm() - circle.radius) <= 2.0f * options.circle_tolerance)
                on_circles.push_back(layer_points[static_cast<std::size_t>(k)][j]);
    }
    if (circles.size() < 2) return std::nullopt;
    const auto median = [&](auto value) {
        std::vector<float> values;
        for (const CircleFit& c : circles) values.push_back(value(c));
        std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
        return values[values.size() / 2];
    };
    Stem stem;
    stem.centre = {median([](const CircleFit& c) { return c.centre.x(); }), median([](const CircleFit& c) { return c.centre.y(); })};
    stem.radius = median([](const CircleFit& c) { return c.radius; });
    int supporting = static_cast<int>(circles.size());
    if (2 * supporting < count && stem.radius >= options.buttressed_stem_radius)
        for (int k = 0; k < lowest_holding; ++k) supporting += is_flare_of(layers[static_cast<std::size_t>(k)], stem, options);
    if (2 * supporting < count) return std::nullopt;
    for (const CircleFit& c : circles) {
        if ((c.centre - stem.centre).norm() > 0.5f * stem.radius) return std::nullopt;            // one trunk, layer above layer
        if (c.radius > 2.0f * stem.radius || 2.0f * c.radius < stem.radius) return std::nullopt;  // ... of one girth
        stem.inliers += c.inliers;
    }
    if (!upright(centres, options.max_stem_lean)) return std::nullopt;
    stem.points = std::move(on_circles);
    return stem;
}

// A thin trunk followed up from the bottom of the slice, layer by layer, for as long as its
// layers hold circles of about one radius, each within a radius and the circle band of the one
// below (a leaning trunk moves by tan(lean) x the layer height between layers); two layers in a
// row that do not continue it end it. Where twigs and leaves start the layers hold other
// circles. nullopt unless the trunk is followed over `min_layers` layers.
std::optional<Stem> follow_trunk_up(const PointCloud& cloud, const std::vector<int>& cluster, float low, float high, int min_layers,
                                    const SegmentOptions& options) {
    const float height = options.trunk_layer_height;
    const int count = std::max(1, static_cast<int>(std::ceil((high - low) / height)));
    std::vector<std::vector<Eigen::Vector2f>> layers(static_cast<std::size_t>(count));
    std::vector<std::vector<int>> layer_points(static_cast<std::size_t>(count));
    for (int i : cluster) {
        const Eigen::Vector3f& p = cloud.positions[static_cast<std::size_t>(i)];
        const auto k = static_cast<std::size_t>(std::min(count - 1, static_cast<int>((p.z() - low) / height)));
        layers[k].push_back(p.head<2>());
        layer_points[k].push_back(i);
    }
    std::vector<CircleFit> run;
    Stem trunk;
    int missed = 0;  // layers in a row that did not continue the trunk
    for (std::size_t k = 0; k < layers.size() && missed < 2; ++k) {
        const CircleFit circle =
                static_cast<int>(layers[k].size()) < options.min_stem_points
                        ? CircleFit{}
                        : fit_circle(layers[k], options.circle_tolerance, options.min_stem_radius, options.max_stem_radius);
        bool continues = circle_holds(circle, layers[k].size(), options);
        if (continues && !run.empty()) {
            const CircleFit& below = run.back();
            const bool same_radius = circle.radius <= 1.5f * below.radius && below.radius <= 1.5f * circle.radius;
            continues = same_radius && (circle.centre - below.centre).norm() <= below.radius + options.circle_tolerance;
        }
        if (!continues) {
            missed += !run.empty();
            continue;
        }
        missed = 0;
        run.push_back(circle);
        for (std::size_t j = 0; j < layers[k].size(); ++j)
            if (std::abs((layers[k][j] - circle.centre).norm() - circle.radius) <= 2.0f * options.circle_tolerance)
                trunk.points.push_back(layer_points[k][j]);
    }
    if (static_cast<int>(run.size()) < min_layers) return std::nullopt;
    std::vector<float> radii;
    for (const CircleFit& c : run) {
        radii.push_back(c.radius);
        trunk.inliers += c.inliers;
    }
    std::nth_element(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(radii.size() / 2), radii.end());
    trunk.radius = radii[radii.size() / 2];
    trunk.centre = run.front().centre;
    return trunk;
}

// A slice cluster is a stem when it spans most of the slice height and a circle of a plausible
// radius holds enough of its points around enough of its circumference (Liang et al. 2012, §2.2),
// standing upright, over the slice's height or else layer by layer (a tapering trunk, or one
// whose visible arc turns with height).
std::optional<Stem> fit_stem(const PointCloud& cloud, const std::vector<float>& height_above_ground, const std::vector<int>& cluster,
                             const SegmentOptions& options) {
    if (static_cast<int>(cluster.size()) < options.min_stem_points) return std::nullopt;
    float low = std::numeric_limits<float>::infinity(), high = -low;
    std::vector<Eigen::Vector2f> xy;
    xy.reserve(cluster.size());
    for (int i : cluster) {
        const Eigen::Vector3f& p = cloud.positions[static_cast<std::size_t>(i)];
        xy.emplace_back(p.x(), p.y());
        low = std::min(low, p.z());
        high = std::max(high, p.z());
    }
    if (high - low < 0.5f * (options.stem_slice_high - options.stem_slice_low)) return std::nullopt;
    const CircleFit circle = fit_circle(xy, options.circle_tolerance, options.min_stem_radius, options.max_stem_radius);
    if (circle_holds(circle, cluster.size(), options)) {
        // Only the points on the circle seed the tree: a branch or a bush touching the stem in
        // the slice must win its points through the graph like any other.
        std::vector<int> on_circle;
        for (std::size_t k = 0; k < cluster.size(); ++k)
            if (std::abs((xy[k] - circle.centre).norm() - circle.radius) <= 2.0f * options.circle_tolerance)
                on_circle.push_back(cluster[k]);
        const std::vector<Eigen::Vector3f> samples = above_ground(cloud, height_above_ground, on_circle);
        if (upright(samples, options.max_stem_lean) && arc_in_every_upper_quarter(samples, circle.centre, options)) {
            // A thin trunk that leans (a crape myrtle's trunks part at 12-24 degrees) is smeared
            // over the slice's height, and with the twigs it carries it holds a circle several
            // times its radius; thin layers of it hold its own.
            const float quarter_slice = 0.25f * (options.stem_slice_high - options.stem_slice_low);
            const int min_layers = static_cast<int>(std::ceil(quarter_slice / options.trunk_layer_height));
            std::optional<Stem> trunk = follow_trunk_up(cloud, cluster, low, high, min_layers, options);
            if (trunk && trunk->radius < 0.5f * circle.radius) return trunk;
            return Stem{circle.centre, circle.radius, circle.inliers, std::move(on_circle)};
        }
    }
    // Points that lean may be a trunk whose visible arc turns with height (occlusion): its
    // layers' circles tell.
    return fit_stem_by_layers(cloud, cluster, low, high, options);
}

}  // namespace

std::vector<Stem> find_stems(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                             const SegmentOptions& options) {
    std::vector<int> slice;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float h = terrain.height_above_ground[i];
        if (vegetation[i] && h >= options.stem_slice_low && h <= options.stem_slice_high) slice.push_back(static_cast<int>(i));
    }
    // Points between the graph's floor and the slice, flattened: a stem continues down to the
    // ground (within 1.5 radii: root flare), a branch or a drooping crown that crosses the slice
    // does not. A thick trunk's flare can reach farther: the synthetic figs of 1.0-1.65 m DBH stand
    // on a skirt of roots 1.9-2.5 radii wide up to 1-1.5 m above the ground, and measured within
    // 1.5 radii they had nothing below them (docs/segment.md, "Thick trunks on buttresses").
    std::vector<Eigen::Vector3f> below;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (vegetation[i] && terrain.height_above_ground[i] < options.stem_slice_low)
            below.emplace_back(cloud.positions[i].x(), cloud.positions[i].y(), 0.0f);
    if (below.empty()) return {};
    const KdTree below_index(below);
    std::vector<int> near;
    std::vector<float> squared;
    const auto reaches_ground = [&](const Stem& stem) {
        const float reach = stem.radius >= options.buttressed_stem_radius ? options.buttressed_foot_reach : options.stem_foot_reach;
        below_index.radius_search(Eigen::Vector3f(stem.centre.x(), stem.centre.y(), 0.0f),
                                  reach * stem.radius + 2.0f * options.circle_tolerance, near, squared,
                                  static_cast<std::size_t>(options.min_stem_points));
        return static_cast<int>(near.size()) >= options.min_stem_points;
    };
    std::vector<Stem> stems;
    const auto stem_of = [&](const std::vector<int>& cluster) {
        std::optional<Stem> stem = fit_stem(cloud, terrain.height_above_ground, cluster, options);
        return stem && reaches_ground(*stem) ? stem : std::nullopt;
    };
    for (const auto& cluster : cluster_slice(cloud, slice, options.stem_cluster_distance)) {
        if (auto stem = stem_of(cluster)) {
            stems.push_back(std::move(*stem));
            continue;
        }
        // A trunk inside a curtain of hanging twigs, or under limbs that fill the slice, joins
        // them at the cluster distance but not at a finer one.
        if (options.stem_subcluster_distance <= 0.0f || static_cast<int>(cluster.size()) < 2 * options.min_stem_points) continue;
        for (const auto& part : cluster_slice(cloud, cluster, options.stem_subcluster_distance))
            if (auto stem = stem_of(part)) stems.push_back(std::move(*stem));
    }
    std::stable_sort(stems.begin(), stems.end(), [](const Stem& a, const Stem& b) { return a.inliers > b.inliers; });
    std::vector<Stem> kept;
    std::vector<float> squared_radii;  // of each kept tree's trunks
    for (auto& stem : stems) {
        const bool duplicate = std::any_of(kept.begin(), kept.end(), [&](const Stem& k) {
            return (k.centre - stem.centre).norm() < std::max(k.radius, stem.radius) + options.circle_tolerance;
        });
        if (duplicate) continue;
        // A second trunk this close is the same tree's (a multi-stemmed tree, an arc of a
        // willow's curtain beside its trunk): its points seed that tree too.
        const auto same_tree = std::find_if(kept.begin(), kept.end(),
                                            [&](const Stem& k) { return (k.centre - stem.centre).norm() < options.stem_merge_distance; });
        if (same_tree != kept.end()) {
            // The trunks of one root collar are alike; a wider circle beside a trunk is an arc
            // of its curtain of twigs or a limb, which adds nothing to its cross-section.
            if (stem.radius <= 1.5f * same_tree->radius)
                squared_radii[static_cast<std::size_t>(same_tree - kept.begin())] += stem.radius * stem.radius;
            same_tree->points.insert(same_tree->points.end(), stem.points.begin(), stem.points.end());
        } else {
            squared_radii.push_back(stem.radius * stem.radius);
            kept.push_back(std::move(stem));
        }
    }
    // A multi-stemmed tree is as wide as the one stem of the same cross-section (its
    // equivalent diameter): sqrt(sum r^2).
    for (std::size_t k = 0; k < kept.size(); ++k) kept[k].radius = std::sqrt(squared_radii[k]);
    // Ids in a reproducible spatial order (south to north, then west to east).
    std::sort(kept.begin(), kept.end(), [](const Stem& a, const Stem& b) {
        return a.centre.y() != b.centre.y() ? a.centre.y() < b.centre.y() : a.centre.x() < b.centre.x();
    });
    return kept;
}

}  // namespace treelobes
