#include "lobes/lobe_split.hpp"

#include "core/error.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <span>

using namespace treelobes;
using namespace treelobes::lobes;
using treelobes::test::error_code_of;

namespace {

// Root (0,0,0) -> 1 (0,0,1) -> 2 (0,0,2) -> 3 (0,0,3), and a side branch 1 -> 4 (1,0,1).
TreeGraph chain_tree() {
    TreeGraph t;
    t.add_node({0, 0, 0}, 0.1f, -1);
    t.add_node({0, 0, 1}, 0.08f, 0);
    t.add_node({0, 0, 2}, 0.05f, 1);
    t.add_node({0, 0, 3}, 0.02f, 2);
    t.add_node({1, 0, 1}, 0.02f, 1);
    return t;
}

}  // namespace

TEST(EdgeConfidence, AverageDistanceToTheEdgeAgainstMidEdgeDiameter) {
    const TreeGraph tree = chain_tree();
    const std::vector<float> d_prime{0.2f, 0.16f, 0.1f, 0.04f, 0.04f};
    // Edge 1 (0..1 m): points 5 cm off the axis; edge 2 (1..2 m): 10 and 30 cm; edge 4: on the axis.
    const std::vector<Eigen::Vector3f> points{{0.05f, 0, 0.5f}, {0, -0.05f, 0.2f}, {0.1f, 0, 1.5f},
                                              {0, 0.3f, 1.5f},  {0.5f, 0, 1.0f},   {0, 0, -1.0f}};
    const std::vector<int> internode{1, 1, 2, 2, 4, -1};
    const EdgeConfidence c = edge_confidence(tree, points, internode, d_prime);
    EXPECT_NEAR(c.mean_distance[1], 0.05f, 1e-6f);
    EXPECT_NEAR(c.mean_distance[2], 0.2f, 1e-6f);
    EXPECT_NEAR(c.mean_distance[4], 0.0f, 1e-6f);
    EXPECT_NEAR(c.threshold[2], 0.13f, 1e-6f);  // mean of d' at both ends
    EXPECT_EQ(c.points[1], 2);
    EXPECT_EQ(c.points[3], 0);
    EXPECT_FALSE(c.low[1]);
    EXPECT_TRUE(c.low[2]);
    EXPECT_FALSE(c.low[3]);  // no points: no evidence against the edge
    EXPECT_FALSE(c.low[4]);
    EXPECT_EQ(c.low_count(), 1u);
}

TEST(EdgeConfidence, RejectsMismatchedSizes) {
    const TreeGraph tree = chain_tree();
    const std::vector<Eigen::Vector3f> points{{0, 0, 0}};
    EXPECT_EQ(error_code_of([&] { edge_confidence(tree, points, std::vector<int>{}, std::vector<float>(5, 0.1f)); }), ExitCode::Usage);
    EXPECT_EQ(error_code_of([&] { edge_confidence(tree, points, std::vector<int>{1}, std::vector<float>(2, 0.1f)); }), ExitCode::Usage);
}

TEST(EdgeConfidence, AMeasuredDiameterRaisesTheThresholdAndNeverLowersIt) {
    const TreeGraph tree = chain_tree();
    const std::vector<float> d_prime{0.2f, 0.16f, 0.1f, 0.04f, 0.04f};
    const std::vector<Eigen::Vector3f> points{{0.1f, 0, 1.5f}, {0, 0.3f, 1.5f}, {0.05f, 0, 0.5f}};
    const std::vector<int> internode{2, 2, 1};
    // Edge 2 (mean distance 0.2 m, allometric threshold 0.13 m) measured at 0.45 m: confident;
    // edge 1 measured below its allometric 0.18 m keeps 0.18 m.
    const std::vector<float> measured{0, 0.05f, 0.45f, 0, 0};
    const EdgeConfidence c = edge_confidence(tree, points, internode, d_prime, measured);
    EXPECT_FLOAT_EQ(c.threshold[2], 0.45f);
    EXPECT_NEAR(c.threshold[1], 0.18f, 1e-6f);
    EXPECT_FALSE(c.low[2]);
    EXPECT_EQ(c.measured_raised, 1u);
    EXPECT_TRUE(edge_confidence(tree, points, internode, d_prime).low[2]);
    EXPECT_EQ(error_code_of([&] { edge_confidence(tree, points, internode, d_prime, std::vector<float>(2, 0.1f)); }), ExitCode::Usage);
}

// Edge 2 (1..2 m, allometric mid-edge d' 0.13 m): bark points 0.1 and 0.3 m off the axis; edge 1
// (0..1 m): two bark points and a leaf 0.9 m out; edge 4: one bark point.
TEST(WoodLobeDiameter, FsTimesTwiceTheMeanBarkDistanceWhereTheEdgeRunsAlongBark) {
    const TreeGraph tree = chain_tree();
    const std::vector<float> d_prime{0.2f, 0.16f, 0.1f, 0.04f, 0.04f};
    const std::vector<Eigen::Vector3f> points{{0.1f, 0, 1.5f},  {0, 0.3f, 1.5f}, {0.05f, 0, 0.5f},
                                              {0, 0.05f, 0.4f}, {0.9f, 0, 0.5f}, {0.9f, 0, 1.0f}};
    const std::vector<int> internode{2, 2, 1, 1, 1, 4};
    const std::vector<char> wood{1, 1, 1, 1, 0, 1};
    WoodMeasurement w;
    w.min_points = 2;
    w.min_share = 0.9;
    w.max_factor = 10;
    const std::vector<float> measured = wood_lobe_diameter(tree, points, internode, wood, d_prime, 0.9f, w);
    EXPECT_NEAR(measured[2], 0.9f * 2 * 0.2f, 1e-6f);
    EXPECT_EQ(measured[1], 0.0f);  // a third of its points are leaves: not an edge along bark
    EXPECT_EQ(measured[4], 0.0f);  // one bark point measures nothing
    EXPECT_EQ(measured[0], 0.0f);  // the root has no edge
    EXPECT_EQ(measured[3], 0.0f);
    w.min_share = 0.5;
    EXPECT_NEAR(wood_lobe_diameter(tree, points, internode, wood, d_prime, 0.9f, w)[1], 0.9f * 2 * 0.05f, 1e-6f);
    w.max_factor = 2;  // at most twice the allometric 0.13 m
    EXPECT_NEAR(wood_lobe_diameter(tree, points, internode, wood, d_prime, 0.9f, w)[2], 0.26f, 1e-6f);
}

TEST(WoodLobeDiameter, RejectsBadOptionsAndSizes) {
    const TreeGraph tree = chain_tree();
    const std::vector<Eigen::Vector3f> points{{0, 0, 0.5f}};
    const std::vector<int> internode{1};
    const std::vector<float> d_prime(5, 0.1f);
    const std::vector<char> wood{1};
    auto code = [&](WoodMeasurement w, std::span<const char> labels, std::span<const float> d) {
        return error_code_of([&] { wood_lobe_diameter(tree, points, internode, labels, d, 1.0f, w); });
    };
    EXPECT_EQ(code({0, 0.9, 2}, wood, d_prime), ExitCode::Usage);
    EXPECT_EQ(code({3, std::numeric_limits<double>::quiet_NaN(), 2}, wood, d_prime), ExitCode::Usage);
    EXPECT_EQ(code({3, 1.5, 2}, wood, d_prime), ExitCode::Usage);
    EXPECT_EQ(code({3, 0.9, 0.5}, wood, d_prime), ExitCode::Usage);
    EXPECT_EQ(code({}, std::vector<char>{}, d_prime), ExitCode::Usage);
    EXPECT_EQ(code({}, wood, std::vector<float>(2, 0.1f)), ExitCode::Usage);
}

TEST(SplitAtLowConfidence, ClusterTakesTheWholeSubtreeAboveTheFirstLowEdge) {
    const TreeGraph tree = chain_tree();
    EdgeConfidence c;
    c.low = {0, 0, 1, 1, 0};  // edge 3 is low too, but it lies beyond edge 2: same cluster
    const std::vector<int> internode{1, 2, 3, 3, 4, 2, -1};
    const MainSplit split = split_at_low_confidence(tree, c, internode);
    EXPECT_EQ(split.main, (std::vector<char>{1, 1, 0, 0, 1}));
    ASSERT_EQ(split.clusters.size(), 1u);
    EXPECT_EQ(split.clusters[0].seed_node, 1);
    EXPECT_EQ(split.clusters[0].first_node, 2);
    EXPECT_EQ(split.clusters[0].nodes, (std::vector<int>{2, 3}));
    EXPECT_EQ(split.clusters[0].points, (std::vector<int>{1, 2, 3, 5}));
}

TEST(SplitAtLowConfidence, OneClusterPerLowEdgeOnSeparatePaths) {
    const TreeGraph tree = chain_tree();
    EdgeConfidence c;
    c.low = {0, 0, 1, 0, 1};
    const std::vector<int> internode{4, 3, 1};
    const MainSplit split = split_at_low_confidence(tree, c, internode);
    ASSERT_EQ(split.clusters.size(), 2u);
    EXPECT_EQ(split.clusters[0].first_node, 2);  // pre-order: main child first
    EXPECT_EQ(split.clusters[0].points, (std::vector<int>{1}));
    EXPECT_EQ(split.clusters[1].first_node, 4);
    EXPECT_EQ(split.clusters[1].seed_node, 1);
    EXPECT_EQ(split.clusters[1].points, (std::vector<int>{0}));
}
