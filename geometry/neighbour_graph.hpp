// The neighbour graph of Livny et al. 2011, §4.1: every point is joined to its k nearest neighbours
// (symmetrised), each edge (u, v) weighted ||u - v||^beta. Separate pieces of the cloud (gaps
// in the scan) are joined by bridging edges, so every point reaches every other: the shortest
// ones, or (direction_weight > 0) for an elongated piece the one its end axis points along.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

namespace treelobes {

class KdTree;

struct NeighbourGraphOptions {
    int neighbours = 10;            // k of the kNN graph (2..64)
    double beta = 1.0;              // edge weight exponent (species parameter, Livny et al. 2011, Table 1)
    float max_edge_length = 0.0f;   // metres; longer kNN edges are dropped before bridging (0 = gap_factor x spacing)
    bool join_components = true;    // add bridging edges until the graph is connected
    float gap_factor = 10.0f;       // automatic max_edge_length in median nearest-neighbour distances: a clump
                                    // of fewer than k points must not reach across a gap with kNN edges
    float direction_weight = 0.0f;  // > 0: an elongated piece joins where its own axis leads (see bridge_cost), 0 = shortest bridges
};

// Undirected graph in compressed rows: the neighbours of vertex i are
// targets[offsets[i] .. offsets[i+1]), sorted by index.
struct NeighbourGraph {
    std::vector<std::uint32_t> offsets;
    std::vector<int> targets;
    std::vector<float> lengths;   // Euclidean edge length (metres)
    std::vector<float> weights;   // length^beta
    std::size_t components = 0;   // connected pieces before bridging
    std::size_t bridges = 0;      // bridging edges added
    float longest_bridge = 0.0f;  // metres

    std::size_t vertex_count() const { return offsets.empty() ? 0 : offsets.size() - 1; }
    std::size_t edge_count() const { return targets.size() / 2; }
};

struct KnnTable;

// `tree` may be passed when a kd-tree over exactly these points exists already, `table` when
// their kNN table (at least `neighbours` wide) does: its first k columns give the edges and
// all of them serve the search for bridges.
NeighbourGraph build_neighbour_graph(std::span<const Eigen::Vector3f> points, const NeighbourGraphOptions& options,
                                     const KdTree* tree = nullptr, const KnnTable* table = nullptr);

// Connected components of a graph: label per vertex, labels 0.. numbered by smallest vertex.
std::vector<int> connected_components(const NeighbourGraph& graph, std::size_t* count = nullptr);

}  // namespace treelobes
