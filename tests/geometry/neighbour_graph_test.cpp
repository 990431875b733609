// The neighbour graph (geometry/neighbour_graph.hpp), with component bridging, on small clouds
// whose answers can be worked out by hand.
#include "core/error.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/neighbour_graph.hpp"
#include "support/point_sets.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace treelobes;
using treelobes::test::add_line;
using treelobes::test::random_points;

TEST(NeighbourGraph, SymmetricSortedRowsWithPowerWeights) {
    const auto points = random_points(500, 3);
    NeighbourGraphOptions options;
    options.neighbours = 6;
    options.beta = 1.7;
    const NeighbourGraph g = build_neighbour_graph(points, options);
    ASSERT_EQ(g.vertex_count(), 500u);
    for (std::size_t i = 0; i < 500; ++i) {
        ASSERT_GE(g.offsets[i + 1] - g.offsets[i], 6u);  // own k neighbours at least
        EXPECT_TRUE(std::is_sorted(g.targets.begin() + g.offsets[i], g.targets.begin() + g.offsets[i + 1]));
        for (std::uint32_t e = g.offsets[i]; e < g.offsets[i + 1]; ++e) {
            const int j = g.targets[e];
            EXPECT_NEAR(g.lengths[e], (points[i] - points[j]).norm(), 1e-6f);
            EXPECT_NEAR(g.weights[e], std::pow(g.lengths[e], 1.7f), 1e-6f);
            // j lists i as well.
            EXPECT_TRUE(std::binary_search(g.targets.begin() + g.offsets[j], g.targets.begin() + g.offsets[j + 1], static_cast<int>(i)));
        }
    }
    EXPECT_THROW(build_neighbour_graph(points, {1, 1.0, 0.0f, true}), Error);
}

TEST(NeighbourGraph, PiecesAreJoinedByTheShortestBridges) {
    // Three lines of 100 points (larger than the exact-search limit for small pieces) and a
    // 3-point clump; gaps of 0.5 m, 0.3 m and 0.2 m.
    std::vector<Eigen::Vector3f> p;
    add_line(p, {0, 0, 0}, {0, 0, 1}, 0.01f);              // A
    add_line(p, {0, 0, 1.5f}, {0, 0, 2.5f}, 0.01f);        // B: 0.5 m above A
    add_line(p, {0.3f, 0, 1.5f}, {1.3f, 0, 1.5f}, 0.01f);  // C: 0.3 m beside B's foot
    p.push_back({0, 0, 2.7f});                             // D: 0.2 m above B
    p.push_back({0, 0.01f, 2.71f});
    p.push_back({0, -0.01f, 2.71f});
    NeighbourGraphOptions options;
    options.neighbours = 4;
    const NeighbourGraph g = build_neighbour_graph(p, options);
    EXPECT_EQ(g.components, 4u);
    EXPECT_EQ(g.bridges, 3u);
    std::size_t pieces = 0;
    connected_components(g, &pieces);
    EXPECT_EQ(pieces, 1u);
    EXPECT_NEAR(g.longest_bridge, 0.5f, 1e-4f);
    // C must join B (0.3 m), not the largest piece: the bridge ends at B's foot (1.5 m).
    const int c_first = 101 + 101;
    bool found = false;
    for (std::uint32_t e = g.offsets[c_first]; e < g.offsets[c_first + 1]; ++e)
        if (std::abs(g.lengths[e] - 0.3f) < 1e-4f) found = true;
    EXPECT_TRUE(found);
}

TEST(NeighbourGraph, ElongatedPieceJoinsAlongItsOwnAxis) {
    // A stem (A) with a branch (B) that bends up to run 0.3 m beside it, and the branch's
    // continuation (C) beyond a 0.4 m occlusion gap. C's nearest foreign points lie 0.3 m
    // sideways on the stem; its own axis leads down to B's top, which is where it belongs.
    std::vector<Eigen::Vector3f> p;
    add_line(p, {0, 0, 0}, {0, 0, 3}, 0.01f);        // A
    add_line(p, {0, 0, 1}, {0.3f, 0, 1.3f}, 0.01f);  // B, joined to A
    add_line(p, {0.3f, 0, 1.31f}, {0.3f, 0, 1.6f}, 0.01f);
    const int c_first = static_cast<int>(p.size());
    add_line(p, {0.3f, 0, 2.0f}, {0.3f, 0, 3.0f}, 0.01f);  // C
    auto bridge_of_c = [&](float weight) {
        NeighbourGraphOptions options;
        options.neighbours = 4;
        options.direction_weight = weight;
        const NeighbourGraph g = build_neighbour_graph(p, options);
        EXPECT_EQ(g.components, 2u);
        EXPECT_EQ(g.bridges, 1u);
        for (int v = c_first; v < static_cast<int>(p.size()); ++v)
            for (std::uint32_t e = g.offsets[v]; e < g.offsets[v + 1]; ++e)
                if (g.targets[e] < c_first) return std::make_pair(v, g.targets[e]);
        return std::make_pair(-1, -1);
    };
    const auto [from, to] = bridge_of_c(2.0f);
    ASSERT_GE(from, 0);
    EXPECT_LT((p[from] - Eigen::Vector3f(0.3f, 0, 2.0f)).norm(), 1e-4f);
    EXPECT_LT((p[to] - Eigen::Vector3f(0.3f, 0, 1.6f)).norm(), 1e-4f);
    // The shortest bridge goes sideways to the stem.
    const auto [side_from, side_to] = bridge_of_c(0.0f);
    ASSERT_GE(side_from, 0);
    EXPECT_NEAR((p[side_from] - p[side_to]).norm(), 0.3f, 1e-4f);
    EXPECT_NEAR(p[side_to].x(), 0.0f, 1e-4f);
    NeighbourGraphOptions bad;
    bad.direction_weight = -1.0f;
    EXPECT_THROW(build_neighbour_graph(p, bad), Error);
}
