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

// Sources whose paths cost more or less than others, per edge: a path from sources[s] pays on
// edge e its cost times 1 + (source_scale[s] - 1) * edge_share[e]. With every share 1 that is a
// multiplicatively weighted partition (a source with a smaller factor reaches farther); a share
// below 1 exempts that part of an edge (the vertical part, say, when the sources differ in how
// far they reach sideways). Each vertex goes to the source whose scaled path to it is cheapest
// among the paths through vertices of the same source, so every region is connected.
struct SourceScaling {
    std::span<const float> source_scale;  // one positive, finite factor per source
    std::span<const float> edge_share;    // per edge, in graph.targets order, each in 0..1; empty = 1 for all
};

// Sizes that differ from the sources' and the edges', or factors and shares out of range, throw
// Error(Internal).
ShortestPaths shortest_paths(const NeighbourGraph& graph, std::span<const int> sources, const SourceScaling& scaling,
                             EdgeCost edge_cost = EdgeCost::Weight);

}  // namespace treelobes
