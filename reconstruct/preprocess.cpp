#include "reconstruct/preprocess.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/point_scatter.hpp"
#include "geometry/ransac_fit.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>

namespace treelobes {

GroundMode parse_ground_mode(const std::string& text) {
    if (text == "auto") return GroundMode::Auto;
    if (text == "remove") return GroundMode::Remove;
    if (text == "keep") return GroundMode::Keep;
    throw Error::usage("--ground must be auto, remove or keep, got '" + text + "'");
}

OutlierTest parse_outlier_test(const std::string& text) {
    if (text == "auto") return OutlierTest::Auto;
    if (text == "global") return OutlierTest::Global;
    if (text == "local") return OutlierTest::Local;
    throw Error::usage("--outlier-test must be auto, global or local, got '" + text + "'");
}

namespace {

void check_options(const PreprocessOptions& o) {
    if (!(o.duplicate_distance >= 0) || !(o.voxel_size >= 0))
        throw Error::usage("preprocess: duplicate distance and voxel size must be >= 0");
    if (o.outlier_neighbours < 0 || o.outlier_neighbours > 64) throw Error::usage("preprocess: outlier neighbours must be in 0..64");
    if (o.table_width < 0 || o.table_width > 64) throw Error::usage("preprocess: table width must be in 0..64");
    if (!(o.outlier_sigma > 0)) throw Error::usage("preprocess: outlier sigma must be > 0");
    if (!(o.outlier_ratio > 0) || !std::isfinite(o.outlier_ratio)) throw Error::usage("preprocess: outlier ratio must be > 0");
    if (!(o.leafy_linear_fraction >= 0 && o.leafy_linear_fraction <= 1))
        throw Error::usage("preprocess: leafy linear fraction must be in [0, 1]");
    if (!(o.ground_tolerance > 0)) throw Error::usage("preprocess: ground tolerance must be > 0");
}

// One representative (the first in input order) per cell of size `cell`; returns, per input
// point, the index of its representative among the returned points.
std::vector<int> merge_cells(const std::vector<Eigen::Vector3f>& input, float cell, std::vector<Eigen::Vector3f>& kept) {
    const std::size_t n = input.size();
    std::vector<int> representative(n);
    if (!(cell > 0)) {
        kept = input;
        std::iota(representative.begin(), representative.end(), 0);
        return representative;
    }
    Eigen::Vector3f low = input[0];
    for (const auto& p : input) low = low.cwiseMin(p);
    std::vector<std::array<std::int64_t, 3>> key(n);
    for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) key[i][a] = static_cast<std::int64_t>(std::floor((input[i][a] - low[a]) / cell));
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });
    // The first input index of each cell represents it; kept points stay in input order.
    std::vector<int> leader(n);
    for (std::size_t i = 0; i < n; ++i) leader[order[i]] = (i > 0 && key[order[i]] == key[order[i - 1]]) ? leader[order[i - 1]] : order[i];
    std::vector<int> kept_index(n, -1);
    for (std::size_t i = 0; i < n; ++i)
        if (leader[i] == static_cast<int>(i)) {
            kept_index[i] = static_cast<int>(kept.size());
            kept.push_back(input[i]);
        }
    for (std::size_t i = 0; i < n; ++i) representative[i] = kept_index[leader[i]];
    return representative;
}

// Mean distance m(i) from each point to its k nearest neighbours (the first k columns of `table`).
std::vector<double> mean_neighbour_distances(const KnnTable& table, std::size_t n, int k) {
    std::vector<double> mean(n);
    for (std::size_t i = 0; i < n; ++i) {
        double m = 0;
        for (int j = 0; j < k; ++j) m += std::sqrt(static_cast<double>(table.row_distances(i)[j]));
        mean[i] = m / k;
    }
    return mean;
}

// Global test: m(i) > mean + sigma * stddev of m over the scan's points off the ground (`ground`
// empty: all of them). Why not the ground's: a terrestrial scan samples the ground near the
// scanner far more densely than a crown, so with its points in the statistics the limit is the
// ground's spacing and the crown's sparse top is cut off (the demo's leaf-off ailanthus: 20,275
// of its 23,175 points ground, 389 of the 2,900 tree points removed, the skeleton 1.2 m short).
std::vector<bool> global_outliers(const std::vector<double>& mean, float sigma, const std::vector<bool>& ground) {
    double sum = 0, sum_sq = 0, count = 0;
    for (std::size_t i = 0; i < mean.size(); ++i) {
        if (!ground.empty() && ground[i]) continue;
        sum += mean[i];
        sum_sq += mean[i] * mean[i];
        ++count;
    }
    if (count == 0) return std::vector<bool>(mean.size(), false);
    const double mu = sum / count, sd = std::sqrt(std::max(0.0, sum_sq / count - mu * mu));
    const double limit = mu + sigma * sd;
    std::vector<bool> outlier(mean.size());
    for (std::size_t i = 0; i < mean.size(); ++i) outlier[i] = mean[i] > limit;
    return outlier;
}

// Local test: of the points the global test flags, only those whose m(i) also exceeds `ratio`
// times the mean m of their own k neighbours, i.e. points much sparser than what surrounds them
// (stray returns in the air); a globally sparse point as sparse as its neighbours stays. Why it
// exists: TLS density falls with range and leaves are sampled far more densely than the twigs
// they hide, so in leafy scans the global limit is set by ground and foliage and cuts the
// sparse samples of thin branches into pieces (synthetic oak: 7 % of the wood removed against
// 2 % of the leaves; most missed branches had lost their points), while a run of sparse samples
// along a twig is as sparse as its neighbours. Why it is not used everywhere: on the real
// wood-only scans the sparse runs the global test removes are crown parts the references partly
// leave out, where the skeleton is also least accurate (WoodSKE OR skeleton -> reference p95
// 0.066 -> 0.091 with the local test, though reference -> skeleton p95 0.26 -> 0.16).
std::vector<bool> local_outliers(const KnnTable& table, const std::vector<double>& mean, int k, float ratio, float sigma,
                                 const std::vector<bool>& ground) {
    std::vector<bool> outlier = global_outliers(mean, sigma, ground);
    for (std::size_t i = 0; i < mean.size(); ++i) {
        if (!outlier[i]) continue;
        double around = 0;
        for (int j = 0; j < k; ++j) around += mean[static_cast<std::size_t>(table.row(i)[j])];
        outlier[i] = mean[i] * k > ratio * around;
    }
    return outlier;
}

// Shape of the scan's 20-point neighbourhoods over the points not `skip`ped (a regular subsample
// of at most 5,000, so the figures are cheap and deterministic): the fractions that lie along a
// line (linearity (l1 - l2) / l1 > 0.8 of their covariance) and on a plane ((l2 - l3) / l1 > 0.8).
struct NeighbourhoodShapes {
    float linear = -1.0f, planar = -1.0f;  // -1: too few points to tell
};

// The neighbourhoods come from `table` (the outlier filter's kNN rows, which leave out the point
// itself: the point and its first 19 neighbours are the 20 nearest, in the same order) when it is
// wide enough, else from kd-tree queries.
NeighbourhoodShapes neighbourhood_shapes(const KdTree& tree, const KnnTable& table, const std::vector<Eigen::Vector3f>& points,
                                         const std::vector<bool>& skip) {
    constexpr int kNeighbours = 20;
    constexpr std::size_t kSamples = 5000;
    std::vector<int> candidates;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!skip[i]) candidates.push_back(static_cast<int>(i));
    if (candidates.size() <= static_cast<std::size_t>(kNeighbours)) return {};
    const std::size_t step = std::max<std::size_t>(1, candidates.size() / kSamples);
    std::vector<int> found;
    std::vector<float> d2;
    std::size_t sampled = 0, linear = 0, planar = 0;
    for (std::size_t c = 0; c < candidates.size(); c += step) {
        const int centre = candidates[c];
        if (table.k >= kNeighbours - 1) {
            const int* row = table.row(static_cast<std::size_t>(centre));
            found.assign(1, centre);
            for (int j = 0; j < kNeighbours - 1 && row[j] >= 0; ++j) found.push_back(row[j]);
        } else {
            tree.knn(points[centre], kNeighbours, found, d2);
        }
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(point_scatter(points, found).scatter, Eigen::EigenvaluesOnly);
        const Eigen::Vector3d l = solver.eigenvalues();  // ascending
        ++sampled;
        linear += l[2] > 0 && l[2] - l[1] > 0.8 * l[2];
        planar += l[2] > 0 && l[1] - l[0] > 0.8 * l[2];
    }
    const double n = static_cast<double>(sampled);
    return {static_cast<float>(static_cast<double>(linear) / n), static_cast<float>(static_cast<double>(planar) / n)};
}

// A leafy crown, told by its neighbourhoods: bark of branches and twigs gives linear ones; leaf
// blades are small plates at every orientation, and in a leafy crown they outnumber the wood
// ~10 to 1, so few neighbourhoods are linear, and few are planar beyond a blade. Linear
// fraction above the ground: 0.11-0.26 on every single-tree TLS/MLS scan of ../shared/data
// (WoodSKE, aRchi, treels pine, AdTree trees) and 0.13-0.34 on leafless synthetic trees,
// against 0.03-0.08 on synthetic leafy TLS scans (the default limit 0.09 lies between); the
// leafy willow (0.15) and birch (0.24), whose hanging twigs or sparse foliage keep them linear,
// stay with the global test. Planar fraction: <= 0.09 on the leafy scans, 0.28 on AdTree's
// house, whose walls must not pass for foliage.
bool looks_leafy(const NeighbourhoodShapes& shapes, float max_linear) {
    constexpr float kMaxPlanar = 0.15f;
    return shapes.linear >= 0 && shapes.linear < max_linear && shapes.planar < kMaxPlanar;
}

// The kNN table of the kept points, read from the table of all points where a row still holds
// `width` kept points (the nearest kept ones, in the same order); rows that lost too many
// neighbours to the filters are queried again on `kept_tree`.
KnnTable kept_neighbours(const KnnTable& all, const std::vector<int>& final_index, const std::vector<int>& source, const KdTree& kept_tree,
                         int width) {
    KnnTable table;
    table.k = width;
    const std::size_t n = source.size(), w = static_cast<std::size_t>(width);
    table.indices.assign(n * w, -1);
    table.squared_distances.assign(n * w, std::numeric_limits<float>::infinity());
    treelobes::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
        std::vector<int> found;
        std::vector<float> d2;
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            int* row = table.indices.data() + i * w;
            float* row_d = table.squared_distances.data() + i * w;
            const int* old_row = all.row(static_cast<std::size_t>(source[i]));
            const float* old_d = all.row_distances(static_cast<std::size_t>(source[i]));
            int filled = 0;
            for (int j = 0; j < all.k && filled < width && old_row[j] >= 0; ++j)
                if (final_index[old_row[j]] >= 0) {
                    row[filled] = final_index[old_row[j]];
                    row_d[filled] = old_d[j];
                    ++filled;
                }
            if (filled == width) continue;
            kept_tree.knn(kept_tree.point(static_cast<int>(i)), width + 1, found, d2);
            std::fill(row, row + w, -1);
            std::fill(row_d, row_d + w, std::numeric_limits<float>::infinity());
            filled = 0;
            for (std::size_t j = 0; j < found.size() && filled < width; ++j) {
                if (found[j] == static_cast<int>(i)) continue;  // the point itself
                row[filled] = found[j];
                row_d[filled] = d2[j];
                ++filled;
            }
        }
    });
    return table;
}

// Spread of a set of points in x and y between the 5th and 95th percentiles (robust extent).
Eigen::Vector2f robust_extent(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& subset) {
    Eigen::Vector2f extent;
    for (int a = 0; a < 2; ++a) {
        std::vector<float> v;
        v.reserve(subset.size());
        for (int i : subset) v.push_back(points[i][a]);
        std::sort(v.begin(), v.end());
        extent[a] = v[v.size() * 95 / 100] - v[v.size() * 5 / 100];
    }
    return extent;
}

// The points not `removed` at most `tolerance` above (or anywhere below) the plane n.p + d = 0.
std::vector<bool> on_ground_plane(const std::vector<Eigen::Vector3f>& points, const std::vector<bool>& removed,
                                  const Eigen::Vector4f& plane, float tolerance) {
    std::vector<bool> ground(points.size(), false);
    const Eigen::Vector3f normal = plane.head<3>();
    for (std::size_t i = 0; i < points.size(); ++i) ground[i] = !removed[i] && normal.dot(points[i]) + plane[3] < tolerance;
    return ground;
}

// Ground: a near-horizontal plane among the lowest points that is wider than any stem. Returns
// the points at most `tolerance` above it (or below it).
std::vector<bool> find_ground(const std::vector<Eigen::Vector3f>& points, const std::vector<bool>& removed, const PreprocessOptions& o,
                              Preprocessed& out) {
    std::vector<bool> ground(points.size(), false);
    if (o.ground == GroundMode::Keep) return ground;
    float z_low = std::numeric_limits<float>::infinity(), z_high = -z_low;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!removed[i]) {
            z_low = std::min(z_low, points[i].z());
            z_high = std::max(z_high, points[i].z());
        }
    const float slab = std::clamp(0.03f * (z_high - z_low), 0.3f, 0.6f);
    std::vector<int> low;
    std::vector<Eigen::Vector3f> low_points;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!removed[i] && points[i].z() < z_low + slab) {
            low.push_back(static_cast<int>(i));
            low_points.push_back(points[i]);
        }
    const PlaneFit plane = fit_plane(low_points, 0.5f * o.ground_tolerance, 1000, 30.0f);
    if (!plane.ok || plane.normal.z() < 0.85f) return ground;
    std::vector<int> inliers;
    for (int k : plane.inliers) inliers.push_back(low[k]);
    const Eigen::Vector2f extent = robust_extent(points, inliers);
    const bool wide = extent.minCoeff() >= o.ground_min_extent;
    const bool substantial = inliers.size() * 5 >= low.size();  // at least 20 % of the bottom slab
    if (o.ground == GroundMode::Auto && !(wide && substantial)) return ground;
    out.ground_found = true;
    out.ground_plane << plane.normal, plane.offset;
    return on_ground_plane(points, removed, out.ground_plane, o.ground_tolerance);
}

}  // namespace

Preprocessed preprocess_cloud(const PointCloud& cloud, const PreprocessOptions& options, const std::string& name) {
    check_options(options);
    if (cloud.size() < 10) throw Error::input(name, "too few points for a tree (" + std::to_string(cloud.size()) + ")");
    Preprocessed out;
    std::vector<Eigen::Vector3f> merged;
    const std::vector<int> representative = merge_cells(cloud.positions, std::max(options.duplicate_distance, options.voxel_size), merged);
    out.duplicates = cloud.size() - merged.size();

    // One kNN query over all points serves the outlier filter and, read through the filters,
    // the table handed on (a few columns wider, so that most rows survive the removals).
    const int k = options.outlier_neighbours;
    const bool filter = k > 0 && merged.size() > static_cast<std::size_t>(k) + 1;
    constexpr int kSpare = 4;
    KnnTable all;
    std::optional<KdTree> merged_tree;
    std::vector<double> mean;
    std::vector<bool> removed(merged.size(), false);
    const auto outliers = [&](bool local, const std::vector<bool>& ground) {
        return local ? local_outliers(all, mean, k, options.outlier_ratio, options.outlier_sigma, ground)
                     : global_outliers(mean, options.outlier_sigma, ground);
    };
    if (filter) {
        all = knn_of_all_points(merged_tree.emplace(merged), std::max(k, options.table_width > 0 ? options.table_width + kSpare : 0));
        mean = mean_neighbour_distances(all, merged.size(), k);
        out.local_outlier_test = options.outlier_test == OutlierTest::Local;
        removed = outliers(out.local_outlier_test, {});
    }
    std::vector<bool> ground = find_ground(merged, removed, options, out);
    std::vector<bool> on_plane;        // every point of the ground plane, outlier or not: none sets the outlier limit
    if (filter && out.ground_found) {  // the test again, with the limit from the points off the plane
        on_plane = on_ground_plane(merged, std::vector<bool>(merged.size(), false), out.ground_plane, options.ground_tolerance);
        removed = outliers(out.local_outlier_test, on_plane);
        ground = on_ground_plane(merged, removed, out.ground_plane, options.ground_tolerance);
    }
    if (filter && options.outlier_test == OutlierTest::Auto) {
        std::vector<bool> skip = removed;
        for (std::size_t i = 0; i < merged.size(); ++i) skip[i] = skip[i] || ground[i];
        const NeighbourhoodShapes shapes = neighbourhood_shapes(*merged_tree, all, merged, skip);
        out.linear_fraction = shapes.linear;
        out.local_outlier_test = looks_leafy(shapes, options.leafy_linear_fraction);
        log_debug(name + ": neighbourhoods " + std::to_string(shapes.linear) + " linear, " + std::to_string(shapes.planar) +
                  " planar: " + (out.local_outlier_test ? "local" : "global") + " outlier test");
        if (out.local_outlier_test) {
            // The ground plane stays the one found without the global test's outliers; points
            // the local test keeps join the ground when they lie on it.
            removed = outliers(true, on_plane);
            if (out.ground_found) ground = on_ground_plane(merged, removed, out.ground_plane, options.ground_tolerance);
        }
    }
    out.outliers = static_cast<std::size_t>(std::count(removed.begin(), removed.end(), true));
    for (std::size_t i = 0; i < merged.size(); ++i)
        if (ground[i]) {
            removed[i] = true;
            ++out.ground;
        }

    std::vector<int> final_index(merged.size(), -1), source;
    for (std::size_t i = 0; i < merged.size(); ++i)
        if (!removed[i]) {
            final_index[i] = static_cast<int>(out.points.size());
            out.points.push_back(merged[i]);
            source.push_back(static_cast<int>(i));
        }
    out.point_of_input.resize(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) out.point_of_input[i] = final_index[representative[i]];
    if (out.points.size() < 10)
        throw Error::input(
                name, "too few points left after removing duplicates, outliers and ground (" + std::to_string(out.points.size()) + ")");
    if (options.table_width > 0) {
        auto index = std::make_shared<const KdTree>(out.points);
        out.neighbours = std::make_shared<const KnnTable>(filter ? kept_neighbours(all, final_index, source, *index, options.table_width)
                                                                 : knn_of_all_points(*index, options.table_width));
        out.index = std::move(index);
    }
    return out;
}

}  // namespace treelobes
