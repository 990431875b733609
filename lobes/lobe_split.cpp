#include "lobes/lobe_split.hpp"

#include "core/error.hpp"

#include <Eigen/Geometry>

#include <algorithm>

namespace treelobes::lobes {

namespace {

float segment_distance(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const Eigen::Vector3f ab = b - a;
    const float length2 = ab.squaredNorm();
    const float t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0f, 1.0f) : 0.0f;
    return (a + t * ab - p).norm();
}

}  // namespace

std::size_t EdgeConfidence::low_count() const { return static_cast<std::size_t>(std::count(low.begin(), low.end(), 1)); }

EdgeConfidence edge_confidence(const TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                               std::span<const float> lobe_diameter) {
    if (point_internode.size() != points.size()) throw Error::usage("edge confidence: one internode per point expected");
    if (lobe_diameter.size() != tree.size()) throw Error::usage("edge confidence: one d' per skeleton node expected");
    const std::size_t n = tree.size();
    EdgeConfidence c;
    c.points.assign(n, 0);
    c.threshold.assign(n, 0.0f);
    c.low.assign(n, 0);
    std::vector<double> sum(n, 0.0);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const int u = point_internode[i];
        if (u < 0) continue;
        if (static_cast<std::size_t>(u) >= n) throw Error::usage("edge confidence: point assigned to a node out of range");
        const int parent = tree.nodes[u].parent;
        const Eigen::Vector3f& b = tree.nodes[u].position;
        sum[u] += segment_distance(points[i], parent < 0 ? b : tree.nodes[parent].position, b);
        ++c.points[u];
    }
    c.mean_distance.assign(n, 0.0f);
    for (std::size_t u = 0; u < n; ++u) {
        const int parent = tree.nodes[u].parent;
        if (parent < 0) continue;
        c.threshold[u] = 0.5f * (lobe_diameter[u] + lobe_diameter[parent]);
        if (c.points[u] == 0) continue;
        c.mean_distance[u] = static_cast<float>(sum[u] / c.points[u]);
        c.low[u] = c.mean_distance[u] > c.threshold[u] ? 1 : 0;
    }
    return c;
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
