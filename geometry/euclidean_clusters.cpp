#include "geometry/euclidean_clusters.hpp"

#include "geometry/kd_tree.hpp"
#include "geometry/union_find.hpp"

#include <unordered_map>

namespace treelobes {

std::vector<std::vector<int>> euclidean_clusters(std::span<const Eigen::Vector3f> points, float distance, std::size_t max_links) {
    std::vector<std::vector<int>> clusters;
    if (points.empty()) return clusters;
    const KdTree index(points);
    UnionFind sets(points.size());
    std::vector<int> near;
    std::vector<float> squared;
    for (std::size_t i = 0; i < points.size(); ++i) {
        index.radius_search(points[i], distance, near, squared, max_links);
        for (int j : near) sets.unite(static_cast<int>(i), j);
    }
    std::unordered_map<int, std::size_t> cluster_of_root;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const auto [it, added] = cluster_of_root.emplace(sets.find(static_cast<int>(i)), clusters.size());
        if (added) clusters.emplace_back();
        clusters[it->second].push_back(static_cast<int>(i));
    }
    return clusters;
}

}  // namespace treelobes
