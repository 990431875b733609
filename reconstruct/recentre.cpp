#include "reconstruct/recentre.hpp"

#include "core/error.hpp"
#include "reconstruct/internode_points.hpp"

#include <algorithm>
#include <cmath>

namespace treelobes {

namespace {

// Where the bark of a thin internode lies across its segment: the mean of the points' lateral
// offsets from the segment's line, then `passes` rounds of Gaussian reweighting around the
// current estimate (sigma^2 = the median squared distance from it, at least `floor^2`), so a
// curtain of leaves or a neighbouring twig in the same internode pulls less than the dense
// ring of bark does. Also returns the weighted RMS distance of the points from that centre:
// about the branch radius for a ring of bark, less for the arc a one-sided scan sees.
struct LateralCentre {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double spread = 0;
};

LateralCentre robust_lateral_centre(const std::vector<Eigen::Vector3d>& lateral, int passes, double floor) {
    LateralCentre out;
    Eigen::Vector3d& c = out.centre;
    for (const auto& r : lateral) c += r;
    c /= static_cast<double>(lateral.size());
    std::vector<double> d2(lateral.size()), w(lateral.size(), 1.0);
    auto distances = [&] {
        for (std::size_t i = 0; i < lateral.size(); ++i) d2[i] = (lateral[i] - c).squaredNorm();
    };
    for (int pass = 0; pass < passes; ++pass) {
        distances();
        std::vector<double> sorted = d2;
        auto mid = sorted.begin() + static_cast<long>(sorted.size() / 2);
        std::nth_element(sorted.begin(), mid, sorted.end());
        const double sigma2 = std::max(*mid, floor * floor);
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        double weight = 0;
        for (std::size_t i = 0; i < lateral.size(); ++i) {
            w[i] = std::exp(-d2[i] / (2.0 * sigma2));
            sum += w[i] * lateral[i];
            weight += w[i];
        }
        if (weight > 0) c = sum / weight;
    }
    distances();
    double sum = 0, weight = 0;
    for (std::size_t i = 0; i < lateral.size(); ++i) {
        sum += w[i] * d2[i];
        weight += w[i];
    }
    out.spread = weight > 0 ? std::sqrt(sum / weight) : 0.0;
    return out;
}

}  // namespace

std::size_t recentre_internodes(TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                                const RecentreOptions& o, const std::vector<bool>& fixed) {
    if (!(o.max_spread > 0.0f) || !std::isfinite(o.max_spread)) throw Error::usage("recentre: maximum spread must be > 0");
    if (o.min_points < 1) throw Error::usage("recentre: minimum points must be >= 1");
    if (o.passes < 0 || o.passes > 20) throw Error::usage("recentre: reweighting passes must be in 0..20");
    if (!(o.dead_band >= 0.0) || !std::isfinite(o.dead_band)) throw Error::usage("recentre: dead band must be >= 0");
    if (!(o.inside_band >= 0.0) || !std::isfinite(o.inside_band)) throw Error::usage("recentre: inside band must be >= 0");
    if (!(o.min_sigma > 0.0) || !std::isfinite(o.min_sigma)) throw Error::usage("recentre: minimum sigma must be > 0");
    if (points.size() != point_internode.size()) throw Error(ExitCode::Internal, "recentre: one internode per point expected");
    if (!fixed.empty() && fixed.size() != tree.size()) throw Error(ExitCode::Internal, "recentre: one fixed flag per node expected");
    if (!o.enabled || tree.size() < 2) return 0;

    const std::size_t n = tree.size();
    const InternodePoints groups = group_by_internode(point_internode, n);
    const std::vector<std::size_t>& start = groups.start;
    const std::vector<int>& grouped = groups.index;

    // Shifts are computed on the input positions, then applied together.
    std::vector<Eigen::Vector3f> shift(n, Eigen::Vector3f::Zero());
    std::vector<Eigen::Vector3d> lateral;
    std::size_t moved = 0;
    for (std::size_t u = 1; u < n; ++u) {
        if (!fixed.empty() && fixed[u]) continue;
        const std::size_t count = start[u + 1] - start[u];
        if (count < static_cast<std::size_t>(o.min_points)) continue;
        const Eigen::Vector3d a = tree.nodes[tree.nodes[u].parent].position.cast<double>();
        const Eigen::Vector3d b = tree.nodes[u].position.cast<double>();
        const double length = (b - a).norm();
        if (length < 1e-9) continue;
        const Eigen::Vector3d t = (b - a) / length;
        lateral.clear();
        for (std::size_t k = start[u]; k < start[u + 1]; ++k) {
            const Eigen::Vector3d q = points[grouped[k]].cast<double>() - a;
            lateral.push_back(q - t * q.dot(t));
        }
        // Thickness: RMS distance of the points from their own centroid across the segment (the
        // radius for a ring of bark, ~0.8 r for a one-sided arc), whatever the node's offset,
        // over the internode and its neighbours above and below: resampling may hand a short
        // internode only a patch of a thick stem's bark, which alone would look thin.
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        double sum_sq = 0;
        std::size_t window = 0;
        auto add_internode = [&](std::size_t v) {
            if (v == 0) return;
            for (std::size_t k = start[v]; k < start[v + 1]; ++k) {
                Eigen::Vector3d q = points[grouped[k]].cast<double>() - a;
                q -= t * q.dot(t);
                mean += q;
                sum_sq += q.squaredNorm();
                ++window;
            }
        };
        add_internode(u);
        add_internode(static_cast<std::size_t>(tree.nodes[u].parent));
        for (int child : tree.nodes[u].children) add_internode(static_cast<std::size_t>(child));
        mean /= static_cast<double>(window);
        const double spread = std::sqrt(std::max(0.0, sum_sq / static_cast<double>(window) - mean.squaredNorm()));
        if (spread >= o.max_spread) continue;
        // Inside its branch: for a ring, or an arc of it wider than ~160 degrees (one-sided scans),
        // the axis lies within one spread of the points' centroid (r sin(a)/a against
        // r sqrt(1 - (sin(a)/a)^2) for a half-angle a), so a node that close stays where the
        // skeleton put it; moving such nodes made the WoodSKE medians worse.
        if (mean.norm() <= o.inside_band * spread) continue;
        // The segment a -> b has no lateral offset from its own line, so the robust centre is the
        // shift, less dead_band x the bark's spread around it (the node is brought to the edge of
        // that band, not across it).
        const LateralCentre c = robust_lateral_centre(lateral, o.passes, o.min_sigma);
        const double distance = c.centre.norm(), band = o.dead_band * c.spread;
        if (distance <= band) continue;  // (rare: the reweighting moved the centre towards the node)
        shift[u] = (c.centre * (1.0 - band / distance)).cast<float>();
        ++moved;
    }
    for (std::size_t u = 1; u < n; ++u) tree.nodes[u].position += shift[u];
    return moved;
}

}  // namespace treelobes
