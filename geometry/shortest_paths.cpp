#include "geometry/shortest_paths.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace treelobes {

namespace {

// Indexed 4-ary min-heap of vertices keyed by (cost, vertex index): each vertex is held at most
// once and its key is lowered in place, so the heap never holds stale entries and stays as
// small as the search front. The vertex index breaks ties, which makes the settling order (and
// so the tree) unique.
class VertexHeap {
public:
    VertexHeap(std::size_t n, const std::vector<double>& cost) : cost_(cost), slot_(n, kOutside) {}
    bool empty() const { return heap_.empty(); }
    bool settled(int v) const { return slot_[v] == kSettled; }
    // Inserts v or moves it up after its cost was lowered.
    void push_or_decrease(int v) {
        if (slot_[v] == kOutside) {
            slot_[v] = static_cast<std::int32_t>(heap_.size());
            heap_.push_back(v);
        }
        sift_up(static_cast<std::size_t>(slot_[v]));
    }
    int pop() {
        const int top = heap_.front();
        slot_[top] = kSettled;
        const int last = heap_.back();
        heap_.pop_back();
        if (!heap_.empty()) {
            heap_.front() = last;
            sift_down(0);
        }
        return top;
    }

private:
    static constexpr std::int32_t kOutside = -1, kSettled = -2;
    bool before(int a, int b) const { return cost_[a] < cost_[b] || (cost_[a] == cost_[b] && a < b); }
    void place(std::size_t i, int v) {
        heap_[i] = v;
        slot_[v] = static_cast<std::int32_t>(i);
    }
    void sift_up(std::size_t i) {
        const int v = heap_[i];
        while (i > 0) {
            const std::size_t parent = (i - 1) / 4;
            if (!before(v, heap_[parent])) break;
            place(i, heap_[parent]);
            i = parent;
        }
        place(i, v);
    }
    void sift_down(std::size_t i) {
        const int v = heap_[i];
        for (;;) {
            const std::size_t first = 4 * i + 1;
            if (first >= heap_.size()) break;
            std::size_t best = first;
            for (std::size_t c = first + 1; c < std::min(first + 4, heap_.size()); ++c)
                if (before(heap_[c], heap_[best])) best = c;
            if (!before(heap_[best], v)) break;
            place(i, heap_[best]);
            i = best;
        }
        place(i, v);
    }

    const std::vector<double>& cost_;
    std::vector<std::int32_t> slot_;  // position in heap_, or kOutside / kSettled
    std::vector<int> heap_;
};

}  // namespace

ShortestPaths shortest_paths(const NeighbourGraph& graph, std::span<const int> sources, EdgeCost edge_cost) {
    const std::vector<float> unscaled(sources.size(), 1.0f);
    return shortest_paths(graph, sources, SourceScaling{unscaled, {}}, edge_cost);
}

ShortestPaths shortest_paths(const NeighbourGraph& graph, std::span<const int> sources, const SourceScaling& scaling,
                             EdgeCost edge_cost) {
    if (scaling.source_scale.size() != sources.size())
        throw Error(ExitCode::Internal, "shortest_paths: " + std::to_string(scaling.source_scale.size()) + " scale factors for " +
                                            std::to_string(sources.size()) + " sources");
    if (!scaling.edge_share.empty() && scaling.edge_share.size() != graph.targets.size())
        throw Error(ExitCode::Internal, "shortest_paths: " + std::to_string(scaling.edge_share.size()) + " edge shares for " +
                                            std::to_string(graph.targets.size()) + " edges");
    for (float scale : scaling.source_scale)
        if (!(scale > 0.0f) || !std::isfinite(scale)) throw Error(ExitCode::Internal, "shortest_paths: scale factors must be positive");
    for (float share : scaling.edge_share)
        if (!(share >= 0.0f && share <= 1.0f)) throw Error(ExitCode::Internal, "shortest_paths: edge shares must be in 0..1");
    const std::size_t n = graph.vertex_count();
    ShortestPaths sp;
    sp.parent.assign(n, -1);
    sp.cost.assign(n, std::numeric_limits<double>::infinity());
    sp.length.assign(n, std::numeric_limits<float>::infinity());
    sp.source.assign(n, -1);
    sp.order.reserve(n);

    VertexHeap heap(n, sp.cost);
    for (std::size_t s = 0; s < sources.size(); ++s) {
        const int v = sources[s];
        if (v < 0 || static_cast<std::size_t>(v) >= n || sp.source[v] >= 0)
            throw Error(ExitCode::Internal, "shortest_paths: invalid or repeated source " + std::to_string(v));
        sp.cost[v] = 0.0;
        sp.length[v] = 0.0f;
        sp.source[v] = static_cast<int>(s);
        heap.push_or_decrease(v);
    }
    const std::vector<float>& step = edge_cost == EdgeCost::Weight ? graph.weights : graph.lengths;
    while (!heap.empty()) {
        const int u = heap.pop();
        const double cost = sp.cost[u];
        sp.order.push_back(u);
        for (std::uint32_t e = graph.offsets[u]; e < graph.offsets[u + 1]; ++e) {
            const int v = graph.targets[e];
            const double share = scaling.edge_share.empty() ? 1.0 : scaling.edge_share[e];
            const double factor = 1.0 + (scaling.source_scale[static_cast<std::size_t>(sp.source[u])] - 1.0) * share;
            const double candidate = cost + factor * step[e];
            if (heap.settled(v) || candidate >= sp.cost[v]) continue;
            sp.cost[v] = candidate;
            sp.parent[v] = u;
            sp.length[v] = sp.length[u] + graph.lengths[e];
            sp.source[v] = sp.source[u];
            heap.push_or_decrease(v);
        }
    }
    return sp;
}

}  // namespace treelobes
