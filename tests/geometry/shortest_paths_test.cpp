// Dijkstra from one or several sources (geometry/shortest_paths.hpp) on hand-checked graphs.
#include "core/error.hpp"
#include "geometry/neighbour_graph.hpp"
#include "geometry/shortest_paths.hpp"
#include "support/point_sets.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace treelobes;
using treelobes::test::add_line;

TEST(ShortestPaths, SingleSourceDistancesAndParents) {
    // An L: 0..1 m along x then 0..1 m along y, points 0.1 m apart.
    std::vector<Eigen::Vector3f> p;
    add_line(p, {0, 0, 0}, {1, 0, 0}, 0.1f);
    add_line(p, {1, 0.1f, 0}, {1, 1, 0}, 0.1f);
    const NeighbourGraph g = build_neighbour_graph(p, {2, 2.0, 0.0f, true});
    const std::vector<int> source{0};
    const ShortestPaths sp = shortest_paths(g, source);
    EXPECT_EQ(sp.parent[0], -1);
    EXPECT_NEAR(sp.length.back(), 2.0f, 1e-4f);
    EXPECT_NEAR(sp.cost.back(), 20 * 0.01, 1e-5);  // 20 edges of 0.1 m, weight 0.1^2
    EXPECT_EQ(sp.order.front(), 0);
    // Parents are settled before their children.
    std::vector<int> rank(p.size());
    for (std::size_t i = 0; i < sp.order.size(); ++i) rank[sp.order[i]] = static_cast<int>(i);
    for (std::size_t v = 1; v < p.size(); ++v) EXPECT_LT(rank[sp.parent[v]], rank[v]);
}

TEST(ShortestPaths, MultiSourceSplitsBetweenSources) {
    std::vector<Eigen::Vector3f> p;
    add_line(p, {0, 0, 0}, {2, 0, 0}, 0.1f);  // 21 points
    const NeighbourGraph g = build_neighbour_graph(p, {2, 1.0, 0.0f, true});
    const std::vector<int> sources{0, 20};
    const ShortestPaths sp = shortest_paths(g, sources);
    for (int v = 0; v < 10; ++v) EXPECT_EQ(sp.source[v], 0);
    for (int v = 11; v <= 20; ++v) EXPECT_EQ(sp.source[v], 1);
    EXPECT_NEAR(sp.length[10], 1.0f, 1e-5f);
    // Same input, same answer (the midpoint's tie is broken the same way).
    EXPECT_EQ(shortest_paths(g, sources).source, sp.source);
    const std::vector<int> repeated{3, 3};
    EXPECT_THROW(shortest_paths(g, repeated), Error);
}

TEST(ShortestPaths, ScaledSourcesReachInProportion) {
    std::vector<Eigen::Vector3f> p;
    add_line(p, {0, 0, 0}, {3, 0, 0}, 0.1f);  // 31 points
    const NeighbourGraph g = build_neighbour_graph(p, {2, 1.0, 0.0f, true});
    const std::vector<int> sources{0, 30};
    // The second source's edges cost twice as much: the first reaches 2 m, the second 1 m (the
    // midpoint of the costs, vertex 20, is a tie).
    const std::vector<float> scale{1.0f, 2.0f};
    const ShortestPaths sp = shortest_paths(g, sources, SourceScaling{scale, {}});
    for (int v = 0; v < 20; ++v) EXPECT_EQ(sp.source[v], 0) << v;
    for (int v = 21; v <= 30; ++v) EXPECT_EQ(sp.source[v], 1) << v;
    EXPECT_NEAR(sp.cost[30 - 5], 2.0 * 5 * 0.1, 1e-6);  // 5 edges of weight 0.1 (beta 1), doubled
    EXPECT_NEAR(sp.length[30 - 5], 0.5f, 1e-5f);         // the length stays Euclidean

    // Where the factor applies to no part of the edges, the sources split in the middle again;
    // where it applies to half of each edge, the second source pays 1.5 times and reaches 1.2 m.
    const std::vector<float> none(g.targets.size(), 0.0f), half(g.targets.size(), 0.5f);
    EXPECT_EQ(shortest_paths(g, sources, SourceScaling{scale, none}).source, shortest_paths(g, sources).source);
    const ShortestPaths halved = shortest_paths(g, sources, SourceScaling{scale, half});
    for (int v = 0; v < 18; ++v) EXPECT_EQ(halved.source[v], 0) << v;
    for (int v = 19; v <= 30; ++v) EXPECT_EQ(halved.source[v], 1) << v;

    // Factors of 1 are the unscaled search.
    const std::vector<float> ones{1.0f, 1.0f};
    EXPECT_EQ(shortest_paths(g, sources, SourceScaling{ones, {}}).source, shortest_paths(g, sources).source);
    const std::vector<float> one_factor{1.0f}, zero{1.0f, 0.0f}, nan{1.0f, std::nanf("")};
    EXPECT_THROW(shortest_paths(g, sources, SourceScaling{one_factor, {}}), Error);
    EXPECT_THROW(shortest_paths(g, sources, SourceScaling{zero, {}}), Error);
    EXPECT_THROW(shortest_paths(g, sources, SourceScaling{nan, {}}), Error);
    const std::vector<float> too_few(3, 1.0f), too_much(g.targets.size(), 1.5f);
    EXPECT_THROW(shortest_paths(g, sources, SourceScaling{scale, too_few}), Error);
    EXPECT_THROW(shortest_paths(g, sources, SourceScaling{scale, too_much}), Error);
}
