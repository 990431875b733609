#include "geometry/neighbour_graph.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/point_scatter.hpp"
#include "geometry/union_find.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace treelobes {

namespace {

using Edge = std::pair<int, int>;  // (smaller index, larger index)

struct Candidate {
    float squared = std::numeric_limits<float>::infinity();
    int a = -1, b = -1;
    // Deterministic choice among equally short bridges.
    bool better(float d, int x, int y) const {
        const auto key = std::minmax(x, y);
        return d < squared || (d == squared && key < std::minmax(a, b));
    }
};

// Median distance from a point to its nearest neighbour.
float median_spacing(const KnnTable& table, std::size_t n) {
    std::vector<float> nearest;
    nearest.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (table.row(i)[0] >= 0) nearest.push_back(table.row_distances(i)[0]);
    if (nearest.empty()) return 0.0f;
    auto mid = nearest.begin() + static_cast<long>(nearest.size() / 2);
    std::nth_element(nearest.begin(), mid, nearest.end());
    return std::sqrt(*mid);
}

// Symmetrised kNN edges no longer than the gap length, without duplicates, sorted.
std::vector<Edge> knn_edges(const KdTree& tree, const KnnTable& table, int k, float max_length, float gap_factor) {
    if (!(max_length > 0)) max_length = gap_factor * median_spacing(table, tree.size());
    const float max_squared = max_length > 0 ? max_length * max_length : std::numeric_limits<float>::infinity();
    const std::size_t n = tree.size();
    // Every edge is filed under its smaller end (a counting sort), then each short bucket is
    // sorted and deduplicated: the list one global sort would give, at a fraction of the cost.
    auto for_each_edge = [&](auto&& visit) {
        for (std::size_t i = 0; i < n; ++i) {
            const int* row = table.row(i);
            const float* d2 = table.row_distances(i);
            for (int j = 0; j < k; ++j)
                if (row[j] >= 0 && d2[j] <= max_squared) visit(std::minmax(static_cast<int>(i), row[j]));
        }
    };
    std::vector<std::uint32_t> start(n + 1, 0);
    for_each_edge([&](Edge e) { ++start[static_cast<std::size_t>(e.first) + 1]; });
    for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
    std::vector<int> larger(start[n]);
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for_each_edge([&](Edge e) { larger[fill[e.first]++] = e.second; });
    std::vector<Edge> edges;
    edges.reserve(larger.size());
    for (std::size_t a = 0; a < n; ++a) {
        const auto first = larger.begin() + start[a], last = larger.begin() + start[a + 1];
        std::sort(first, last);
        const auto end = std::unique(first, last);
        for (auto b = first; b != end; ++b) edges.emplace_back(static_cast<int>(a), *b);
    }
    return edges;
}

// Bridges read from neighbour rows: the first neighbour of p in another component is p's
// nearest foreign point. A component's best such pair is its exact shortest bridge when it is
// no longer than the k-th neighbour distance of every member whose row holds no foreign point
// (their nearest foreign point lies farther than that). Returns which components are settled;
// the others go through the exact searches below.
std::vector<bool> bridges_from_table(const KnnTable& table, const std::vector<int>& label, std::size_t count,
                                     std::vector<Candidate>& best) {
    std::vector<float> bound(count, std::numeric_limits<float>::infinity());
    for (std::size_t p = 0; p < label.size(); ++p) {
        const int* row = table.row(p);
        const float* d2 = table.row_distances(p);
        bool found = false;
        for (int j = 0; j < table.k && row[j] >= 0; ++j)
            if (label[row[j]] != label[p]) {
                if (best[label[p]].better(d2[j], static_cast<int>(p), row[j])) best[label[p]] = {d2[j], static_cast<int>(p), row[j]};
                found = true;
                break;
            }
        // A short row (a tiny cloud) leaves no bound: every other point was listed.
        if (!found && row[table.k - 1] >= 0) bound[label[p]] = std::min(bound[label[p]], d2[table.k - 1]);
    }
    std::vector<bool> exact(count);
    for (std::size_t c = 0; c < count; ++c) exact[c] = best[c].a >= 0 && best[c].squared <= bound[c];
    return exact;
}

// Nearest point outside component `label` for every point of a small component: among the
// size+1 nearest neighbours of a point at most `size` lie in its own component, so the first
// foreign one is the nearest foreign point (exact).
void small_component_bridges(const KdTree& tree, const std::vector<int>& label, const std::vector<std::vector<int>>& members,
                             std::size_t small_limit, const std::vector<bool>& exact, std::vector<Candidate>& best) {
    std::vector<int> found;
    std::vector<float> d2;
    for (std::size_t c = 0; c < members.size(); ++c) {
        if (members[c].size() > small_limit || exact[c]) continue;
        for (int p : members[c]) {
            tree.knn(tree.point(p), static_cast<int>(members[c].size()) + 1, found, d2);
            for (std::size_t j = 0; j < found.size(); ++j)
                if (label[found[j]] != static_cast<int>(c)) {
                    if (best[c].better(d2[j], p, found[j])) best[c] = {d2[j], p, found[j]};
                    break;
                }
        }
    }
}

// Exact nearest foreign point of a large component: an upper bound from the largest component
// (one kd-tree shared by all), then a kd-tree over the foreign points inside the component's
// bounding box grown by that bound. A gap-separated crown fragment thus joins the nearest
// fragment, not a far point of the main stem.
void large_component_bridges(std::span<const Eigen::Vector3f> points, const std::vector<int>& label,
                             const std::vector<std::vector<int>>& members, std::size_t small_limit, std::size_t largest,
                             const std::vector<bool>& exact, std::vector<Candidate>& best) {
    bool any = false;
    for (std::size_t c = 0; c < members.size(); ++c) any |= c != largest && members[c].size() > small_limit && !exact[c];
    if (!any) return;
    std::vector<Eigen::Vector3f> main_points;
    main_points.reserve(members[largest].size());
    for (int p : members[largest]) main_points.push_back(points[p]);
    const KdTree main_tree(main_points);
    for (std::size_t c = 0; c < members.size(); ++c) {
        if (c == largest || members[c].size() <= small_limit || exact[c]) continue;
        Eigen::Vector3f low = points[members[c].front()], high = low;
        for (int p : members[c]) {
            float d2 = 0;
            const int q = members[largest][main_tree.nearest(points[p], &d2)];
            if (best[c].better(d2, p, q)) best[c] = {d2, p, q};
            low = low.cwiseMin(points[p]);
            high = high.cwiseMax(points[p]);
        }
        const float reach = std::sqrt(best[c].squared);
        low.array() -= reach;
        high.array() += reach;
        std::vector<int> foreign;
        std::vector<Eigen::Vector3f> foreign_points;
        for (std::size_t q = 0; q < points.size(); ++q)
            if (label[q] != static_cast<int>(c) && label[q] != static_cast<int>(largest) && (points[q].array() >= low.array()).all() &&
                (points[q].array() <= high.array()).all()) {
                foreign.push_back(static_cast<int>(q));
                foreign_points.push_back(points[q]);
            }
        if (foreign.empty()) continue;
        const KdTree near_tree(foreign_points);
        for (int p : members[c]) {
            float d2 = 0;
            const int q = foreign[near_tree.nearest(points[p], &d2)];
            if (best[c].better(d2, p, q)) best[c] = {d2, p, q};
        }
    }
}

// One end of an elongated piece: its extreme point along the piece's principal axis and the
// direction the piece leaves by there (the principal axis of its last third, pointing out).
struct PieceEnd {
    int point = -1;
    Eigen::Vector3f outward = Eigen::Vector3f::Zero();
};

Eigen::Vector3f principal_axis(std::span<const Eigen::Vector3f> points, const std::vector<int>& members, double* elongation = nullptr) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(point_scatter(points, members).scatter);
    if (elongation) *elongation = solver.eigenvalues()[2] / std::max(solver.eigenvalues()[1], 1e-12);
    return solver.eigenvectors().col(2).cast<float>();
}

// The two ends of a piece of at least `min_points` points whose principal variance is at least
// `min_elongation` times the next (a stretch of branch, not a crumb or a patch of bark); none
// otherwise, since such a piece has no direction to continue in.
std::vector<PieceEnd> piece_ends(std::span<const Eigen::Vector3f> points, const std::vector<int>& members, std::size_t min_points,
                                 double min_elongation) {
    if (members.size() < min_points) return {};
    double elongation = 0;
    const Eigen::Vector3f axis = principal_axis(points, members, &elongation);
    if (elongation < min_elongation) return {};
    std::vector<float> t(members.size());
    for (std::size_t i = 0; i < members.size(); ++i) t[i] = points[members[i]].dot(axis);
    const auto [low, high] = std::minmax_element(t.begin(), t.end());
    const float third = (*high - *low) / 3.0f;
    std::vector<PieceEnd> ends;
    for (const float sign : {-1.0f, 1.0f}) {
        const float extreme = sign < 0 ? *low : *high;
        std::vector<int> tail;
        for (std::size_t i = 0; i < members.size(); ++i)
            if (sign * (t[i] - extreme) >= -third) tail.push_back(members[i]);
        Eigen::Vector3f outward = sign * axis;
        if (tail.size() >= 4) {
            const Eigen::Vector3f local = principal_axis(points, tail);
            outward = local.dot(outward) < 0 ? -local : local;
        }
        ends.push_back({members[static_cast<std::size_t>((sign < 0 ? low : high) - t.begin())], outward});
    }
    return ends;
}

// Cost of a bridge from a point of an elongated piece to a foreign point: its length, times
// 1 + weight (1 - cos) where cos is the cosine between the bridge and the direction the piece
// leaves by at its nearest end (the better of the two). A branch broken by an occlusion gap
// thus continues along its own axis to the part it came from instead of jumping sideways to
// the nearest bark, and a piece lying beside a stem pays for a side join.
float bridge_cost(const Eigen::Vector3f& from, const Eigen::Vector3f& to, std::span<const PieceEnd> ends, float weight) {
    const Eigen::Vector3f d = to - from;
    const float length = d.norm();
    if (length <= 0) return 0.0f;
    float best_cos = -1.0f;
    for (const PieceEnd& e : ends) best_cos = std::max(best_cos, d.dot(e.outward) / length);
    return length * (1.0f + weight * (1.0f - best_cos));
}

// Replaces each elongated piece's shortest bridge by the cheapest bridge (bridge_cost) from one
// of its ends when that is cheaper. Candidates lie within the shortest bridge's cost of an end
// (no farther point can be cheaper).
void directed_bridges(std::span<const Eigen::Vector3f> points, const KdTree& tree, const std::vector<int>& label,
                      const std::vector<std::vector<int>>& members, std::size_t largest, float weight, std::vector<Candidate>& best) {
    constexpr std::size_t kMinPoints = 5;   // a few samples of a sparse twig already show its direction
    constexpr double kMinElongation = 9.0;  // length at least 3 times the width
    constexpr std::size_t kMaxCandidates = 4096;
    std::vector<int> found;
    std::vector<float> d2;
    for (std::size_t c = 0; c < members.size(); ++c) {
        if (c == largest || best[c].a < 0) continue;
        const std::vector<PieceEnd> ends = piece_ends(points, members[c], kMinPoints, kMinElongation);
        if (ends.empty()) continue;
        float cost = bridge_cost(points[best[c].a], points[best[c].b], ends, weight);
        const float shortest_cost = cost;
        Candidate chosen = best[c];
        for (const PieceEnd& e : ends) {
            tree.radius_search(points[e.point], shortest_cost, found, d2, kMaxCandidates);
            for (std::size_t j = 0; j < found.size(); ++j) {
                if (label[found[j]] == static_cast<int>(c)) continue;
                const float q = bridge_cost(points[e.point], points[found[j]], std::span(&e, 1), weight);
                if (q < cost) {
                    cost = q;
                    chosen = {d2[j], e.point, found[j]};
                }
            }
        }
        best[c] = chosen;
    }
}

// Borůvka-style joining: each round every component except the largest gets its shortest
// bridge (see above), or its directed one (directed_bridges), then all bridges are added. Returns the bridging edges.
std::vector<Edge> bridge_components(std::span<const Eigen::Vector3f> points, const KdTree& tree, const KnnTable& table,
                                    float direction_weight, UnionFind& sets, float& longest) {
    constexpr std::size_t kSmall = 64;
    std::vector<Edge> bridges;
    const int n = static_cast<int>(points.size());
    for (;;) {
        std::vector<int> label(n, -1), root_label(n, -1);
        std::vector<std::vector<int>> members;
        for (int i = 0; i < n; ++i) {
            const int r = sets.find(i);
            if (root_label[r] < 0) {
                root_label[r] = static_cast<int>(members.size());
                members.emplace_back();
            }
            label[i] = root_label[r];
            members[label[i]].push_back(i);
        }
        if (members.size() <= 1) return bridges;
        std::size_t largest = 0;
        for (std::size_t c = 1; c < members.size(); ++c)
            if (members[c].size() > members[largest].size()) largest = c;
        std::vector<Candidate> best(members.size());
        std::vector<bool> exact = bridges_from_table(table, label, members.size(), best);
        log_debug("bridging round: " + std::to_string(members.size()) + " pieces, " +
                  std::to_string(std::count(exact.begin(), exact.end(), false)) + " need an exact search");
        small_component_bridges(tree, label, members, kSmall, exact, best);
        large_component_bridges(points, label, members, kSmall, largest, exact, best);
        if (direction_weight > 0) directed_bridges(points, tree, label, members, largest, direction_weight, best);
        for (std::size_t c = 0; c < members.size(); ++c) {
            const Candidate& e = best[c];
            if (e.a < 0 || !sets.unite(e.a, e.b)) continue;
            bridges.push_back(std::minmax(e.a, e.b));
            longest = std::max(longest, std::sqrt(e.squared));
        }
    }
}

NeighbourGraph to_compressed_rows(std::span<const Eigen::Vector3f> points, const std::vector<Edge>& edges, double beta) {
    NeighbourGraph g;
    const std::size_t n = points.size();
    g.offsets.assign(n + 1, 0);
    for (const auto& [a, b] : edges) {
        ++g.offsets[a + 1];
        ++g.offsets[b + 1];
    }
    for (std::size_t i = 0; i < n; ++i) g.offsets[i + 1] += g.offsets[i];
    g.targets.resize(g.offsets[n]);
    std::vector<std::uint32_t> fill(g.offsets.begin(), g.offsets.end() - 1);
    // Edges are sorted pairs (a < b): row i receives its smaller neighbours (as b) in increasing
    // order before its larger ones (as a), so every row comes out sorted without a sort.
    for (const auto& [a, b] : edges) {
        g.targets[fill[a]++] = b;
        g.targets[fill[b]++] = a;
    }
    g.lengths.resize(g.targets.size());
    g.weights.resize(g.targets.size());
    const float exponent = static_cast<float>(beta);
    treelobes::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i)
            for (std::uint32_t e = g.offsets[i]; e < g.offsets[i + 1]; ++e) {
                const float length = (points[i] - points[g.targets[e]]).norm();
                g.lengths[e] = length;
                g.weights[e] = exponent == 1.0f ? length : std::pow(length, exponent);
            }
    });
    return g;
}

}  // namespace

NeighbourGraph build_neighbour_graph(std::span<const Eigen::Vector3f> points, const NeighbourGraphOptions& options, const KdTree* tree,
                                     const KnnTable* given) {
    if (options.neighbours < 2 || options.neighbours > 64)
        throw Error::usage("neighbour graph: neighbours must be in 2..64, got " + std::to_string(options.neighbours));
    if (!(options.beta > 0.0) || !std::isfinite(options.beta)) throw Error::usage("neighbour graph: beta must be > 0");
    if (!(options.gap_factor > 0.0f)) throw Error::usage("neighbour graph: gap factor must be > 0");
    if (!(options.direction_weight >= 0.0f) || !std::isfinite(options.direction_weight))
        throw Error::usage("neighbour graph: direction weight must be >= 0");
    std::unique_ptr<KdTree> own;
    if (!tree || tree->size() != points.size()) {
        own = std::make_unique<KdTree>(points);
        tree = own.get();
    }
    const auto t0 = std::chrono::steady_clock::now();
    KnnTable own_table;
    if (!given || given->k < options.neighbours || given->indices.size() != points.size() * static_cast<std::size_t>(given->k)) {
        own_table = knn_of_all_points(*tree, options.neighbours);
        given = &own_table;
    }
    const KnnTable& table = *given;
    std::vector<Edge> edges = knn_edges(*tree, table, options.neighbours, options.max_edge_length, options.gap_factor);
    const auto t1 = std::chrono::steady_clock::now();
    UnionFind sets(points.size());
    for (const auto& [a, b] : edges) sets.unite(a, b);
    std::size_t components = 0;
    for (std::size_t i = 0; i < points.size(); ++i) components += sets.find(static_cast<int>(i)) == static_cast<int>(i);

    float longest = 0.0f;
    std::vector<Edge> bridges;
    if (options.join_components) bridges = bridge_components(points, *tree, table, options.direction_weight, sets, longest);
    const auto t2 = std::chrono::steady_clock::now();
    // Both lists are sorted (bridges after a sort of their own): merging keeps the whole sorted.
    std::sort(bridges.begin(), bridges.end());
    const auto middle = static_cast<std::ptrdiff_t>(edges.size());
    edges.insert(edges.end(), bridges.begin(), bridges.end());
    std::inplace_merge(edges.begin(), edges.begin() + middle, edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

    NeighbourGraph graph = to_compressed_rows(points, edges, options.beta);
    graph.components = components;
    graph.bridges = bridges.size();
    graph.longest_bridge = longest;
    const auto t3 = std::chrono::steady_clock::now();
    auto seconds = [](auto a, auto b) { return std::to_string(std::chrono::duration<double>(b - a).count()); };
    log_debug("neighbour graph: kNN edges " + seconds(t0, t1) + " s, bridging " + seconds(t1, t2) + " s (" + std::to_string(components) +
              " pieces), rows " + seconds(t2, t3) + " s");
    return graph;
}

std::vector<int> connected_components(const NeighbourGraph& graph, std::size_t* count) {
    const std::size_t n = graph.vertex_count();
    std::vector<int> label(n, -1);
    std::vector<int> stack;
    int next = 0;
    for (std::size_t s = 0; s < n; ++s) {
        if (label[s] >= 0) continue;
        label[s] = next;
        stack.assign(1, static_cast<int>(s));
        while (!stack.empty()) {
            const int u = stack.back();
            stack.pop_back();
            for (std::uint32_t e = graph.offsets[u]; e < graph.offsets[u + 1]; ++e)
                if (label[graph.targets[e]] < 0) {
                    label[graph.targets[e]] = next;
                    stack.push_back(graph.targets[e]);
                }
        }
        ++next;
    }
    if (count) *count = static_cast<std::size_t>(next);
    return label;
}

}  // namespace treelobes
