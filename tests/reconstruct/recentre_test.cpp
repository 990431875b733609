// Lateral re-centring of thin internodes on their points (reconstruct/recentre.hpp), alone and
// inside the whole pipeline.
#include "core/error.hpp"
#include "reconstruct/recentre.hpp"
#include "reconstruct/reconstruct_tree.hpp"
#include "support/synthetic_clouds.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <random>

using namespace treelobes;
using test::Segment;

namespace {

// A straight chain of 10 internodes along +x, every node `offset` to the side (+y) of a branch
// of radius 1 cm on the x axis; each bark point belongs to the internode covering its x.
struct ChainFixture {
    TreeGraph tree;
    std::vector<Eigen::Vector3f> points;
    std::vector<int> internode;
    explicit ChainFixture(float offset, float radius = 0.01f, float visible = 1.0f) {
        tree.add_node({0, offset, 0}, 0, -1);
        for (int k = 1; k <= 10; ++k) tree.add_node({0.1f * static_cast<float>(k), offset, 0}, 0, k - 1);
        std::mt19937 rng(3);
        test::add_cylinder(points, {{0, 0, 0}, {1, 0, 0}, radius}, 20000.0f, rng, visible);
        for (const auto& p : points) internode.push_back(std::clamp(static_cast<int>(std::ceil(p.x() / 0.1f)), 1, 10));
    }
};

}  // namespace

TEST(Recentre, ThinInternodesMoveAcrossOntoTheirPoints) {
    for (const double band : {0.0, 0.5}) {
        ChainFixture f(0.05f);
        RecentreOptions o;
        o.dead_band = band;  // 5 cm off a 1 cm branch: outside it, whatever inside_band
        EXPECT_EQ(recentre_internodes(f.tree, f.points, f.internode, o), 10u);
        EXPECT_EQ(f.tree.nodes[0].position.y(), 0.05f);  // the root stays
        for (std::size_t u = 1; u < f.tree.size(); ++u) {
            const Eigen::Vector3f p = f.tree.nodes[u].position;
            EXPECT_NEAR(p.x(), 0.1f * static_cast<float>(u), 1e-5f) << "node " << u << " slid along the branch";
            // Onto the axis, or to the dead band's edge: half the bark's spread (the 1 cm radius).
            const float d = std::hypot(p.y(), p.z());
            if (band == 0.0)
                EXPECT_LT(d, 0.003f) << "node " << u;
            else
                EXPECT_NEAR(d, 0.005f, 0.002f) << "node " << u;
        }
    }
}

TEST(Recentre, NodesInsideTheirBranchStay) {
    ChainFixture f(0.008f);  // 8 mm off the axis of a 1 cm branch: inside it
    EXPECT_EQ(recentre_internodes(f.tree, f.points, f.internode, {}), 0u);
    for (std::size_t u = 0; u < f.tree.size(); ++u) EXPECT_EQ(f.tree.nodes[u].position.y(), 0.008f);
}

TEST(Recentre, ThickOneSidedStemStaysOnItsFittedAxis) {
    // Bark of a 30 cm stem seen from one side: the centroid lies ~19 cm off the axis, where the
    // skeleton's circle fits already put the nodes right.
    ChainFixture f(0.0f, 0.30f, 0.5f);
    const TreeGraph before = f.tree;
    EXPECT_EQ(recentre_internodes(f.tree, f.points, f.internode, {}), 0u);
    for (std::size_t u = 0; u < f.tree.size(); ++u) EXPECT_EQ(f.tree.nodes[u].position, before.nodes[u].position);
}

TEST(Recentre, DisabledOrTooFewPointsLeavesTheTreeAlone) {
    ChainFixture f(0.05f);
    RecentreOptions off;
    off.enabled = false;
    EXPECT_EQ(recentre_internodes(f.tree, f.points, f.internode, off), 0u);
    RecentreOptions sparse;
    sparse.min_points = 1000000;
    EXPECT_EQ(recentre_internodes(f.tree, f.points, f.internode, sparse), 0u);
    for (std::size_t u = 0; u < f.tree.size(); ++u) EXPECT_EQ(f.tree.nodes[u].position.y(), 0.05f);
}

TEST(Recentre, RejectsBadOptions) {
    ChainFixture f(0.0f);
    RecentreOptions o;
    o.max_spread = 0.0f;
    EXPECT_EQ(test::error_code_of([&] { recentre_internodes(f.tree, f.points, f.internode, o); }), ExitCode::Usage);
    o = {};
    o.min_points = 0;
    EXPECT_EQ(test::error_code_of([&] { recentre_internodes(f.tree, f.points, f.internode, o); }), ExitCode::Usage);
    o = {};
    o.dead_band = -1.0;
    EXPECT_EQ(test::error_code_of([&] { recentre_internodes(f.tree, f.points, f.internode, o); }), ExitCode::Usage);
}

TEST(Recentre, LeavesSharingTheInternodePullLessThanTheBark) {
    // Bark of a 1 cm branch plus a sparse curtain of leaf points 6-16 cm under it, all in the
    // same internodes; the skeleton runs 5 cm above the branch.
    ChainFixture f(0.0f);
    for (auto& node : f.tree.nodes) node.position.z() = 0.05f;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const std::size_t bark = f.points.size();
    for (std::size_t i = 0; i < bark / 3; ++i) {
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const float z = -0.06f - 0.1f * unit(rng), y = 0.1f * (unit(rng) - 0.5f), x = unit(rng);
        const Eigen::Vector3f p(x, y, z);
        f.points.push_back(p);
        f.internode.push_back(std::clamp(static_cast<int>(std::ceil(p.x() / 0.1f)), 1, 10));
    }
    RecentreOptions robust, plain;
    robust.dead_band = plain.dead_band = 0.0;
    robust.inside_band = plain.inside_band = 0.0;
    robust.max_spread = plain.max_spread = 0.1f;  // the curtain widens the internodes
    plain.passes = 0;
    TreeGraph plain_tree = f.tree;
    recentre_internodes(plain_tree, f.points, f.internode, plain);
    recentre_internodes(f.tree, f.points, f.internode, robust);
    for (std::size_t u = 1; u < f.tree.size(); ++u) {
        EXPECT_LT(std::abs(f.tree.nodes[u].position.z()), 0.008f) << "node " << u;
        EXPECT_LT(plain_tree.nodes[u].position.z(), -0.02f) << "node " << u << ": the plain centroid is pulled into the leaves";
    }
}

TEST(Recentre, PipelineKeepsCleanBranchesOnTheirAxesForAnyThreadCount) {
    const auto segments = test::y_tree();
    const PointCloud cloud = test::cloud_from(segments, 6000.0f, 9, 0.6f);  // one-sided, as a TLS scan
    ReconstructOptions on, off;
    off.recentre.enabled = false;
    const TreeReconstruction with = reconstruct_tree(cloud, on, "y"), without = reconstruct_tree(cloud, off, "y");
    ASSERT_EQ(with.skeleton.size(), without.skeleton.size());  // only positions change
    EXPECT_EQ(with.point_internode, without.point_internode);
    double d_with = 0, d_without = 0;
    for (std::size_t u = 1; u < with.skeleton.size(); ++u) {
        d_with += test::distance_to_axes(with.skeleton.nodes[u].position, segments);
        d_without += test::distance_to_axes(without.skeleton.nodes[u].position, segments);
    }
    EXPECT_LE(d_with, 1.05 * d_without + 1e-4) << "re-centring moved nodes of a clean one-sided scan off the axes";
    TreeReconstruction one;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one = reconstruct_tree(cloud, on, "y");
    }
    ASSERT_EQ(one.skeleton.size(), with.skeleton.size());
    for (std::size_t u = 0; u < one.skeleton.size(); ++u) EXPECT_EQ(one.skeleton.nodes[u].position, with.skeleton.nodes[u].position);
    EXPECT_EQ(one.summary.recentred_nodes, with.summary.recentred_nodes);
}
