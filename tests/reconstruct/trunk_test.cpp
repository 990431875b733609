// fit_trunk: circles fitted to slices of a synthetic stem of known radius give its DBH, base
// diameter and foot; a branch leaving the stem does not count as stem.
#include "reconstruct/trunk.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

using namespace treelobes;

namespace {

// A vertical stem (node 0 at the foot, node 1 at `height`) sampled as a cylinder surface of
// radius `r` around (cx, cy): a point every 2 degrees and every centimetre.
struct Stem {
    std::vector<Eigen::Vector3f> points;
    std::vector<int> internode;
    TreeGraph tree;
};

Stem stem(float r, float height, float cx = 0.0f, float cy = 0.0f) {
    Stem s;
    s.tree.add_node({cx, cy, 0.0f}, 0.0f, -1);
    s.tree.add_node({cx, cy, height}, 0.0f, 0);
    for (float z = 0.0f; z <= height; z += 0.01f)
        for (int a = 0; a < 180; ++a) {
            const float t = static_cast<float>(a) * 2.0f * std::numbers::pi_v<float> / 180.0f;
            s.points.push_back({cx + r * std::cos(t), cy + r * std::sin(t), z});
            s.internode.push_back(1);
        }
    return s;
}

}  // namespace

TEST(Trunk, DiametersOfACylinderAreTwiceItsRadius) {
    const Stem s = stem(0.15f, 3.0f, 2.0f, -1.0f);
    const TrunkFit fit = fit_trunk(s.points, s.internode, s.tree);
    ASSERT_TRUE(fit.dbh_fitted);
    EXPECT_NEAR(fit.dbh, 0.30f, 0.005f);
    ASSERT_TRUE(fit.base_fitted);
    EXPECT_NEAR(fit.base_diameter, 0.30f, 0.005f);
    ASSERT_TRUE(fit.foot_fitted);
    EXPECT_NEAR(fit.foot_centre.x(), 2.0f, 0.01f);
    EXPECT_NEAR(fit.foot_centre.y(), -1.0f, 0.01f);
    ASSERT_FALSE(fit.slices.empty());
    for (const StemSlice& slice : fit.slices) EXPECT_TRUE(slice.good) << "slice at " << slice.height << " m";
}

TEST(Trunk, PointsOffTheMainAxisAreNotStem) {
    // A thin side branch (node 2) at breast height: its points belong to another internode and
    // must not widen the breast-height circle.
    Stem s = stem(0.10f, 3.0f);
    s.tree.add_node({1.0f, 0.0f, 1.3f}, 0.0f, 0);
    for (float x = 0.10f; x <= 1.0f; x += 0.005f)
        for (int a = 0; a < 36; ++a) {
            const float t = static_cast<float>(a) * 2.0f * std::numbers::pi_v<float> / 36.0f;
            s.points.push_back({x, 0.02f * std::cos(t), 1.3f + 0.02f * std::sin(t)});
            s.internode.push_back(2);
        }
    const TrunkFit fit = fit_trunk(s.points, s.internode, s.tree);
    ASSERT_TRUE(fit.dbh_fitted);
    EXPECT_NEAR(fit.dbh, 0.20f, 0.005f);
}

TEST(Trunk, APartialArcIsNotTrusted) {
    // Only a 60-degree arc of the stem was seen: below min_coverage, no slice is good.
    Stem s;
    s.tree.add_node({0, 0, 0}, 0.0f, -1);
    s.tree.add_node({0, 0, 3}, 0.0f, 0);
    for (float z = 0.0f; z <= 3.0f; z += 0.01f)
        for (int a = 0; a < 30; ++a) {
            const float t = static_cast<float>(a) * 2.0f * std::numbers::pi_v<float> / 180.0f;
            s.points.push_back({0.2f * std::cos(t), 0.2f * std::sin(t), z});
            s.internode.push_back(1);
        }
    const TrunkFit fit = fit_trunk(s.points, s.internode, s.tree);
    EXPECT_FALSE(fit.dbh_fitted);
    EXPECT_FALSE(fit.base_fitted);
}

// A skeleton whose first nodes hook off the stem's axis inside it (as the first geodesic bins
// around the root give them): the nodes below the highest good slice move onto the axis the
// slices give; the one above them, and the branch beside, stay where they were.
TEST(Trunk, AHookedAxisAtTheFootIsAlignedWithTheStem) {
    Stem s = stem(0.2f, 3.0f, 1.0f, 2.0f);
    TreeGraph hooked;
    hooked.add_node({1.0f, 2.0f, 0.0f}, 0.0f, -1);
    hooked.add_node({0.85f, 2.1f, 0.25f}, 0.0f, 0);
    hooked.add_node({0.9f, 2.05f, 0.6f}, 0.0f, 1);
    hooked.add_node({1.02f, 2.0f, 1.2f}, 0.0f, 2);
    hooked.add_node({1.03f, 2.01f, 3.0f}, 0.0f, 3);
    hooked.add_node({1.5f, 2.0f, 0.6f}, 0.0f, 2);  // a side branch, not on the main axis
    for (int& internode : s.internode) internode = 4;
    const TrunkFit fit = fit_trunk(s.points, s.internode, hooked);
    ASSERT_TRUE(fit.foot_fitted);
    EXPECT_EQ(align_trunk_base(hooked, fit), 4u);  // the root and nodes 1-3
    for (int node = 0; node < 4; ++node) {
        EXPECT_NEAR(hooked.nodes[node].position.x(), 1.0f, 0.01f) << node;
        EXPECT_NEAR(hooked.nodes[node].position.y(), 2.0f, 0.01f) << node;
    }
    EXPECT_NEAR(hooked.nodes[1].position.z(), 0.25f, 1e-6f);  // heights are kept
    EXPECT_EQ(hooked.nodes[4].position, Eigen::Vector3f(1.03f, 2.01f, 3.0f));
    EXPECT_EQ(hooked.nodes[5].position, Eigen::Vector3f(1.5f, 2.0f, 0.6f));

    TrunkFit nothing_fitted;
    EXPECT_EQ(align_trunk_base(hooked, nothing_fitted), 0u);
}

TEST(Trunk, AHiddenTrunkJoinsTheFootToTheRoot) {
    // A crown skeleton beginning 10 m up: the root, its main child and a lateral with a twig.
    TreeGraph crown;
    crown.add_node({0.2f, 0, 10}, 0.1f, -1);
    crown.add_node({1, 0, 11}, 0.05f, 0);
    crown.add_node({0, 0, 11}, 0.08f, 0);
    crown.add_node({0, 0.5f, 11.5f}, 0.02f, 1);
    crown.nodes[0].children = {2, 1};  // main child first, not in index order
    const Eigen::Vector3f foot(0, 0, 0);
    TreeGraph tree = crown;
    const std::size_t added = add_hidden_trunk(tree, foot, 0.5f);
    ASSERT_EQ(added, 21u);  // ceil(10.002 / 0.5): internodes of at most 0.5 m
    ASSERT_EQ(tree.size(), crown.size() + added);
    tree.validate("hidden trunk");
    EXPECT_EQ(tree.nodes[0].position, foot);
    for (std::size_t i = 1; i < added; ++i) {
        EXPECT_EQ(tree.nodes[i].parent, static_cast<int>(i) - 1);
        EXPECT_LE(tree.edge_length(static_cast<int>(i)), 0.5f + 1e-5f);
    }
    for (std::size_t v = 0; v < crown.size(); ++v) {  // the old nodes, shifted, with their order of children
        const TreeNode& n = tree.nodes[v + added];
        EXPECT_EQ(n.position, crown.nodes[v].position);
        EXPECT_EQ(n.parent, v == 0 ? static_cast<int>(added) - 1 : crown.nodes[v].parent + static_cast<int>(added));
        ASSERT_EQ(n.children.size(), crown.nodes[v].children.size());
        for (std::size_t k = 0; k < n.children.size(); ++k) EXPECT_EQ(n.children[k], crown.nodes[v].children[k] + static_cast<int>(added));
    }
    // A root within one internode of the foot, or below it, gets no trunk.
    TreeGraph low = crown;
    EXPECT_EQ(add_hidden_trunk(low, {0, 0, 9.6f}, 0.5f), 0u);
    EXPECT_EQ(add_hidden_trunk(low, {0, 0, 12}, 0.5f), 0u);
    EXPECT_EQ(low.size(), crown.size());
}
