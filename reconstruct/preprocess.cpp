#include "reconstruct/preprocess.hpp"

#include "core/error.hpp"
#include "reconstruct/kd_tree.hpp"
#include "reconstruct/ransac_fit.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

namespace treelobes {

GroundMode parse_ground_mode(const std::string& text) {
    if (text == "auto") return GroundMode::Auto;
    if (text == "remove") return GroundMode::Remove;
    if (text == "keep") return GroundMode::Keep;
    throw Error::usage("--ground must be auto, remove or keep, got '" + text + "'");
}

namespace {

void check_options(const PreprocessOptions& o) {
    if (!(o.duplicate_distance >= 0) || !(o.voxel_size >= 0)) throw Error::usage("preprocess: duplicate distance and voxel size must be >= 0");
    if (o.outlier_neighbours < 0 || o.outlier_neighbours > 64) throw Error::usage("preprocess: outlier neighbours must be in 0..64");
    if (o.table_width < 0 || o.table_width > 64) throw Error::usage("preprocess: table width must be in 0..64");
    if (!(o.outlier_sigma > 0)) throw Error::usage("preprocess: outlier sigma must be > 0");
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
    for (std::size_t i = 0; i < n; ++i)
        leader[order[i]] = (i > 0 && key[order[i]] == key[order[i - 1]]) ? leader[order[i - 1]] : order[i];
    std::vector<int> kept_index(n, -1);
    for (std::size_t i = 0; i < n; ++i)
        if (leader[i] == static_cast<int>(i)) {
            kept_index[i] = static_cast<int>(kept.size());
            kept.push_back(input[i]);
        }
    for (std::size_t i = 0; i < n; ++i) representative[i] = kept_index[leader[i]];
    return representative;
}

// Statistical outlier removal: mean distance to the k nearest neighbours per point (the first
// k columns of `table`), points beyond mean + sigma * stddev of that statistic are flagged.
std::vector<bool> statistical_outliers(const KnnTable& table, std::size_t n, int k, float sigma) {
    std::vector<bool> outlier(n, false);
    std::vector<double> mean(n);
    double sum = 0, sum_sq = 0;
    for (std::size_t i = 0; i < n; ++i) {
        double m = 0;
        for (int j = 0; j < k; ++j) m += std::sqrt(static_cast<double>(table.row_distances(i)[j]));
        mean[i] = m / k;
        sum += mean[i];
        sum_sq += mean[i] * mean[i];
    }
    const double count = static_cast<double>(n);
    const double mu = sum / count, sd = std::sqrt(std::max(0.0, sum_sq / count - mu * mu));
    const double limit = mu + sigma * sd;
    for (std::size_t i = 0; i < n; ++i) outlier[i] = mean[i] > limit;
    return outlier;
}

// The kNN table of the kept points, read from the table of all points where a row still holds
// `width` kept points (the nearest kept ones, in the same order); rows that lost too many
// neighbours to the filters are queried again on `kept_tree`.
KnnTable kept_neighbours(const KnnTable& all, const std::vector<int>& final_index, const std::vector<int>& source,
                         const KdTree& kept_tree, int width) {
    KnnTable table;
    table.k = width;
    const std::size_t n = source.size(), w = static_cast<std::size_t>(width);
    table.indices.assign(n * w, -1);
    table.squared_distances.assign(n * w, std::numeric_limits<float>::infinity());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
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

// Ground: a near-horizontal plane among the lowest points that is wider than any stem. Returns
// the points at most `tolerance` above it (or below it).
std::vector<bool> find_ground(const std::vector<Eigen::Vector3f>& points, const std::vector<bool>& removed,
                              const PreprocessOptions& o, Preprocessed& out) {
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
    for (std::size_t i = 0; i < points.size(); ++i)
        ground[i] = !removed[i] && plane.signed_distance(points[i]) < o.ground_tolerance;
    return ground;
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
    if (filter) all = knn_of_all_points(KdTree(merged), std::max(k, options.table_width > 0 ? options.table_width + kSpare : 0));
    std::vector<bool> removed = filter ? statistical_outliers(all, merged.size(), k, options.outlier_sigma)
                                       : std::vector<bool>(merged.size(), false);
    out.outliers = static_cast<std::size_t>(std::count(removed.begin(), removed.end(), true));
    const std::vector<bool> ground = find_ground(merged, removed, options, out);
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
        throw Error::input(name, "too few points left after removing duplicates, outliers and ground (" +
                                     std::to_string(out.points.size()) + ")");
    if (options.table_width > 0) {
        auto index = std::make_shared<const KdTree>(out.points);
        out.neighbours = std::make_shared<const KnnTable>(filter ? kept_neighbours(all, final_index, source, *index, options.table_width)
                                                                 : knn_of_all_points(*index, options.table_width));
        out.index = std::move(index);
    }
    return out;
}

}  // namespace treelobes
