// Euclidean clusters (single linkage): points closer than a distance are linked, and the
// clusters are the linked sets. Used for the stem slices of the terrestrial segmentation and the
// trunks at breast height of the DBH measure.
#pragma once

#include <Eigen/Core>

#include <span>
#include <vector>

namespace treelobes {

// Clusters as indices into `points`, each in increasing order; clusters ordered by their first
// point. Each point links to at most its `max_links` nearest neighbours within `distance`, which
// bounds the work in dense clouds (a dense surface still links through its neighbours).
std::vector<std::vector<int>> euclidean_clusters(std::span<const Eigen::Vector3f> points, float distance, std::size_t max_links = 16);

}  // namespace treelobes
