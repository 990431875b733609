#include "classify/crown.hpp"

#include <algorithm>
#include <numeric>

namespace treelobes::classify {

namespace {

constexpr std::uint8_t kGround = 2, kLowNoise = 7, kHighNoise = 18;

// Indices sorted by height, highest first (stable: equal heights keep their order).
std::vector<std::size_t> by_height_descending(const PointCloud& cloud, const std::vector<std::size_t>& indices) {
    std::vector<std::size_t> order = indices;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return cloud.positions[a].z() > cloud.positions[b].z(); });
    return order;
}

// Number of leading points (highest first) to drop as high outliers: each is more than `gap`
// above the next lower point. At most half of the points: a crown is never taken for an outlier.
std::size_t high_outlier_count(const PointCloud& cloud, const std::vector<std::size_t>& order, double gap) {
    std::size_t k = 0;
    while (k + 1 < order.size() && 2 * (k + 1) <= order.size() && cloud.positions[order[k]].z() - cloud.positions[order[k + 1]].z() > gap)
        ++k;
    return k;
}

// Position (in the descending order, after the outliers) of the first point below the
// understorey gap, or order.size() when there is none.
std::size_t understorey_start(const PointCloud& cloud, const std::vector<std::size_t>& order, std::size_t first, float ground,
                              const CrownOptions& options) {
    if (first >= order.size()) return order.size();
    const double top = cloud.positions[order[first]].z() - ground;
    const double gap = std::max(options.understorey_gap_m, options.understorey_gap_fraction * top);
    for (std::size_t k = first; k + 1 < order.size(); ++k) {
        const double upper = cloud.positions[order[k]].z() - ground, lower = cloud.positions[order[k + 1]].z() - ground;
        if (upper - lower > gap && lower < 0.5 * top) return k + 1;
    }
    return order.size();
}

}  // namespace

CrownExtraction extract_crown(const PointCloud& cloud, const CrownOptions& options) {
    CrownExtraction out;
    out.counts.input = cloud.size();
    const bool classified = cloud.classification.size() == cloud.size() && !cloud.classification.empty();
    std::vector<std::size_t> vegetation;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const std::uint8_t c = classified ? cloud.classification[i] : 0;
        if (c == kLowNoise || c == kHighNoise) {
            ++out.counts.noise;
        } else if (c == kGround) {
            ++out.counts.ground;
            const float z = cloud.positions[i].z();
            out.ground_z = out.ground_z ? std::min(*out.ground_z, z) : z;
        } else {
            vegetation.push_back(i);
        }
    }
    out.counts.ground_found = out.ground_z.has_value();
    if (vegetation.empty()) {  // only ground or noise: keep everything rather than nothing
        out.crown = cloud;
        out.counts.noise = out.counts.ground = 0;
        return out;
    }
    const auto order = by_height_descending(cloud, vegetation);
    const std::size_t first = high_outlier_count(cloud, order, options.outlier_gap_m);
    out.counts.high_outliers = first;
    std::size_t end = order.size();
    if (out.ground_z) end = understorey_start(cloud, order, first, *out.ground_z, options);
    out.counts.understorey = order.size() - end;
    std::vector<std::size_t> keep(order.begin() + static_cast<std::ptrdiff_t>(first), order.begin() + static_cast<std::ptrdiff_t>(end));
    std::sort(keep.begin(), keep.end());  // input order: the crown's attributes stay aligned and reproducible
    out.crown = cloud.subset(keep);
    return out;
}

}  // namespace treelobes::classify
