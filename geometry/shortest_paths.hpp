// Dijkstra's shortest-path tree on the neighbour graph (the one Dijkstra of the project):
// single source (the tree base) or many sources at once, as used to grow several trees of a
// plot at the same time (each vertex then records which source reached it).
#pragma once

#include "geometry/neighbour_graph.hpp"

#include <span>
#include <vector>

namespace treelobes {

struct ShortestPaths {
    std::vector<int> parent;    // predecessor on the shortest path; -1 for sources and unreached vertices
    std::vector<double> cost;   // sum of edge weights from the nearest source; +inf when unreached
    std::vector<float> length;  // Euclidean length of that path (metres, the geodesic distance)
    std::vector<int> source;    // position in `sources` of the source that reached the vertex; -1 unreached
    std::vector<int> order;     // reached vertices in the order they were settled (parents first)
};

// What a path costs: the sum of the graph's weights ||u-v||^beta (the shortest-path tree of
// Livny et al. 2011, §4.1) or of the Euclidean edge lengths (true geodesic distances on the graph).
enum class EdgeCost { Weight, Length };

// Ties are broken by vertex index, so the result is deterministic. Duplicate or out-of-range
// sources throw Error(Internal).
ShortestPaths shortest_paths(const NeighbourGraph& graph, std::span<const int> sources, EdgeCost edge_cost = EdgeCost::Weight);

}  // namespace treelobes
