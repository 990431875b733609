#include "lobes/lobe_split.hpp"

#include "core/error.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <utility>

namespace treelobes::lobes {

namespace {

float segment_distance(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const Eigen::Vector3f ab = b - a;
    const float length2 = ab.squaredNorm();
    const float t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0f, 1.0f) : 0.0f;
    return (a + t * ab - p).norm();
}

// Per node, the mean distance of the points of the edge parent -> node to that edge and their
// count; only points with `counted[i]` != 0 when `counted` is not empty. The root has none.
struct EdgeDistances {
    std::vector<float> mean;
    std::vector<int> count;
};

EdgeDistances edge_distances(const TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                             std::span<const char> counted) {
    if (point_internode.size() != points.size()) throw Error::usage("edge confidence: one internode per point expected");
    const std::size_t n = tree.size();
    std::vector<double> sum(n, 0.0);
    EdgeDistances d{std::vector<float>(n, 0.0f), std::vector<int>(n, 0)};
    for (std::size_t i = 0; i < points.size(); ++i) {
        const int u = point_internode[i];
        if (u < 0 || (!counted.empty() && !counted[i])) continue;
        if (static_cast<std::size_t>(u) >= n) throw Error::usage("edge confidence: point assigned to a node out of range");
        const int parent = tree.nodes[u].parent;
        const Eigen::Vector3f& b = tree.nodes[u].position;
        sum[u] += segment_distance(points[i], parent < 0 ? b : tree.nodes[parent].position, b);
        ++d.count[u];
    }
    for (std::size_t u = 0; u < n; ++u)
        if (d.count[u] > 0 && tree.nodes[u].parent >= 0) d.mean[u] = static_cast<float>(sum[u] / d.count[u]);
    return d;
}

// d' at the middle of the edge parent -> node (the mean of both ends): d(u) falls to 0 at the
// tips, so d' at the upper end alone would make every tip edge low-confidence.
float mid_edge(std::span<const float> lobe_diameter, const TreeGraph& tree, std::size_t u) {
    return 0.5f * (lobe_diameter[u] + lobe_diameter[static_cast<std::size_t>(tree.nodes[u].parent)]);
}

}  // namespace

std::size_t EdgeConfidence::low_count() const { return static_cast<std::size_t>(std::count(low.begin(), low.end(), 1)); }

EdgeConfidence edge_confidence(const TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                               std::span<const float> lobe_diameter, std::span<const float> measured_lobe_diameter) {
    if (lobe_diameter.size() != tree.size()) throw Error::usage("edge confidence: one d' per skeleton node expected");
    if (!measured_lobe_diameter.empty() && measured_lobe_diameter.size() != tree.size())
        throw Error::usage("edge confidence: one measured d' per skeleton node expected");
    EdgeDistances distances = edge_distances(tree, points, point_internode, {});
    EdgeConfidence c;
    c.mean_distance = std::move(distances.mean);
    c.points = std::move(distances.count);
    c.threshold.assign(tree.size(), 0.0f);
    c.low.assign(tree.size(), 0);
    for (std::size_t u = 0; u < tree.size(); ++u) {
        if (tree.nodes[u].parent < 0) continue;
        c.threshold[u] = mid_edge(lobe_diameter, tree, u);
        if (!measured_lobe_diameter.empty() && measured_lobe_diameter[u] > c.threshold[u]) {
            c.threshold[u] = measured_lobe_diameter[u];
            ++c.measured_raised;
        }
        if (c.points[u] > 0) c.low[u] = c.mean_distance[u] > c.threshold[u] ? 1 : 0;
    }
    return c;
}

void check_wood_measurement(const WoodMeasurement& w) {
    if (w.min_points < 1 || !(w.min_share >= 0 && w.min_share <= 1) || !(w.max_factor >= 1))
        throw Error::usage("lobes: the wood measurement needs min_points >= 1, min_share in 0..1 and max_factor >= 1");
}

std::vector<float> wood_lobe_diameter(const TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                                      std::span<const char> wood, std::span<const float> lobe_diameter, float fs,
                                      const WoodMeasurement& measurement) {
    check_wood_measurement(measurement);
    if (wood.size() != points.size()) throw Error::usage("wood diameters: one wood label per point expected");
    if (lobe_diameter.size() != tree.size()) throw Error::usage("wood diameters: one d' per skeleton node expected");
    const EdgeDistances bark = edge_distances(tree, points, point_internode, wood);
    const std::vector<int> all = edge_distances(tree, points, point_internode, {}).count;
    std::vector<float> measured(tree.size(), 0.0f);
    for (std::size_t u = 0; u < tree.size(); ++u) {
        const auto wood_points = static_cast<std::size_t>(bark.count[u]);
        if (tree.nodes[u].parent < 0 || wood_points < measurement.min_points ||
            static_cast<double>(wood_points) < measurement.min_share * all[u])
            continue;
        const float cap = static_cast<float>(measurement.max_factor) * mid_edge(lobe_diameter, tree, u);
        measured[u] = std::min(fs * 2.0f * bark.mean[u], cap);
    }
    return measured;
}

MainSplit split_at_low_confidence(const TreeGraph& tree, const EdgeConfidence& confidence, std::span<const int> point_internode) {
    MainSplit split;
    split.main.assign(tree.size(), 0);
    if (tree.empty()) return split;
    std::vector<int> cluster_of(tree.size(), -1);
    for (int u : tree.preorder()) {  // parents come before children
        const int parent = tree.nodes[u].parent;
        if (parent < 0) {
            split.main[u] = 1;
        } else if (cluster_of[parent] >= 0) {
            cluster_of[u] = cluster_of[parent];
        } else if (confidence.low[u]) {
            cluster_of[u] = static_cast<int>(split.clusters.size());
            split.clusters.push_back({parent, u, {}, {}});
        } else {
            split.main[u] = 1;
        }
        if (cluster_of[u] >= 0) split.clusters[cluster_of[u]].nodes.push_back(u);
    }
    for (std::size_t i = 0; i < point_internode.size(); ++i) {
        const int u = point_internode[i];
        if (u >= 0 && cluster_of[u] >= 0) split.clusters[cluster_of[u]].points.push_back(static_cast<int>(i));
    }
    return split;
}

}  // namespace treelobes::lobes
