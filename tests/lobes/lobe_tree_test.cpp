#include "geometry/closed_mesh.hpp"
#include "lobes/lobe_tree.hpp"
#include "lobes/tlobe_io.hpp"

#include "core/error.hpp"
#include "support/synthetic_clouds.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace treelobes;
using namespace treelobes::lobes;

namespace {

// A scanned trunk (0..3 m, r 12 cm) carrying a crown: a ball of foliage points of radius 0.9 m
// centred 0.8 m above the trunk top. The bark edges are confident, the crown's are not.
PointCloud trunk_and_crown(std::size_t* crown_points = nullptr) {
    PointCloud cloud = test::cloud_from({{{0, 0, 0}, {0, 0, 3.0f}, 0.12f}}, 2500.0f);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-0.9f, 0.9f);
    std::size_t added = 0;
    while (added < 5000) {
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const float z = u(rng), y = u(rng), x = u(rng);
        const Eigen::Vector3f p(x, y, z);
        if (p.norm() > 0.9f) continue;
        cloud.positions.push_back(p + Eigen::Vector3f(0, 0, 3.8f));
        ++added;
    }
    if (crown_points) *crown_points = added;
    return cloud;
}

struct Built {
    TreeReconstruction reconstruction;
    LobeTree tree;
    LobeReport report;
};

Built build(const PointCloud& cloud, double fs, const LobeOptions& lobe_options = {}) {
    ReconstructOptions ro;
    ro.allometry.fs = fs;
    Built b{reconstruct_tree(cloud, ro, "trunk_and_crown"), {}, {}};
    b.tree = build_lobe_tree(cloud, b.reconstruction, ro, "test", lobe_options, &b.report);
    return b;
}

}  // namespace

TEST(LobeTree, CrownBecomesClosedLobesSeededOnTheTrunk) {
    std::size_t crown = 0;
    const PointCloud cloud = trunk_and_crown(&crown);
    const Built b = build(cloud, 1.0);
    ASSERT_GE(b.tree.lobes.size(), 1u);
    EXPECT_GE(b.report.lobe_points, crown / 2);  // most of the crown is in lobes
    EXPECT_GE(b.tree.skeleton.size(), 2u);       // the trunk stays explicit
    double lobe_volume = 0;
    for (const Lobe& lobe : b.tree.lobes) {
        EXPECT_TRUE(check_closed(lobe.mesh).closed());
        EXPECT_GT(lobe.volume(), 0.0);
        EXPECT_LE(lobe.mesh.faces.size(), LobeOptions{}.max_lobe_faces);
        ASSERT_GE(lobe.seed_node, 0);
        ASSERT_LT(static_cast<std::size_t>(lobe.seed_node), b.tree.skeleton.size());
        EXPECT_NEAR(lobe.seed_direction.norm(), 1.0f, 1e-4f);
        EXPECT_GT(b.tree.seed_thickness(lobe), 0.0f);
        lobe_volume += lobe.volume();
    }
    // The crown ball holds 3.05 m^3; lobes hull most of it and nothing far beyond.
    EXPECT_GT(lobe_volume, 1.0);
    EXPECT_LT(lobe_volume, 3.2);
    EXPECT_EQ(b.tree.fs, 1.0);
    EXPECT_EQ(b.tree.species, "test");
}

TEST(LobeTree, SmallerFsPutsMorePointsIntoLobesAndOutputIsDeterministic) {
    const PointCloud cloud = trunk_and_crown();
    const Built wide = build(cloud, 1.0);
    const Built narrow = build(cloud, 0.2);
    EXPECT_GE(narrow.report.low_confidence_edges, wide.report.low_confidence_edges);
    EXPECT_GE(narrow.report.lobe_points, wide.report.lobe_points);
    EXPECT_LE(narrow.tree.skeleton.size(), wide.tree.skeleton.size());
    const Built again = build(cloud, 1.0);
    EXPECT_TRUE(encode_tlobe(again.tree) == encode_tlobe(wide.tree)) << "same input, different .tlobe bytes";
}

TEST(LobeTree, RejectsAReconstructionOfAnotherCloud) {
    const PointCloud cloud = trunk_and_crown();
    ReconstructOptions ro;
    const TreeReconstruction r = reconstruct_tree(cloud, ro, "x");
    PointCloud other = cloud;
    other.positions.pop_back();
    EXPECT_THROW(build_lobe_tree(other, r, ro, ""), Error);
}

TEST(LobeTree, DroppedPointsNearTheCrownJoinTheLobeOccupancy) {
    // Isolated points 0.3 m outside the crown ball are dropped as outliers by the reconstruction;
    // with a reach they join the lobe's occupancy points, a point 3 m away and ground do not.
    PointCloud cloud = trunk_and_crown();
    const std::size_t base = cloud.size();
    for (int k = 0; k < 6; ++k) {
        const float a = static_cast<float>(k) * 1.047f;
        cloud.positions.emplace_back(1.2f * std::cos(a), 1.2f * std::sin(a), 3.8f);
    }
    cloud.positions.emplace_back(4.0f, 0.0f, 3.8f);
    cloud.classification.assign(cloud.size(), 1);
    cloud.positions.emplace_back(0.0f, 1.2f, 3.8f);
    cloud.classification.push_back(2);  // ground class: never attached
    ReconstructOptions ro;
    const TreeReconstruction r = reconstruct_tree(cloud, ro, "outliers");
    std::size_t dropped = 0;
    for (std::size_t i = base; i < cloud.size(); ++i) dropped += r.point_internode[i] < 0 ? 1 : 0;
    ASSERT_EQ(dropped, cloud.size() - base);  // the isolated points were all dropped
    LobeReport off, on;
    const LobeTree without = build_lobe_tree(cloud, r, ro, "", {}, &off);
    LobeOptions o;
    o.dropped_point_reach = 0.5;
    const LobeTree with = build_lobe_tree(cloud, r, ro, "", o, &on);
    EXPECT_EQ(off.dropped_points_attached, 0u);
    std::size_t extra = 0;
    ASSERT_EQ(with.lobes.size(), without.lobes.size());
    for (std::size_t l = 0; l < with.lobes.size(); ++l) {
        EXPECT_EQ(with.lobes[l].points, without.lobes[l].points);  // the cluster itself is unchanged
        extra += with.lobes[l].cluster_points.size() - without.lobes[l].cluster_points.size();
    }
    EXPECT_EQ(extra, on.dropped_points_attached);
    EXPECT_EQ(on.dropped_points_attached, 6u);
}

// With wood/leaf labels on the points named as the input's own (LobeOptions::leaf_label_attribute),
// each lobe records the share of its cluster's points on leaves; labels not named (a synthetic
// scan's truth) are not used, and without labels the share is unknown (-1).
TEST(LobeTree, LobesRecordTheirLeafShareFromWoodLabels) {
    PointCloud cloud = trunk_and_crown();
    const Built unlabelled = build(cloud, 1.0);
    for (const Lobe& lobe : unlabelled.tree.lobes) EXPECT_LT(lobe.leaf_share, 0.0f);
    // The crown ball's upper half is leaf (0), everything else wood (1).
    ExtraAttribute& wood = cloud.add_extra("wood", AttributeType::UInt8, 1.0);
    for (std::size_t i = 0; i < cloud.size(); ++i) wood.values[i] = cloud.positions[i].z() > 3.8f ? 0.0 : 1.0;
    for (const Lobe& lobe : build(cloud, 1.0).tree.lobes) EXPECT_LT(lobe.leaf_share, 0.0f);  // not named: not used
    LobeOptions named;
    named.leaf_label_attribute = "wood";
    const Built labelled = build(cloud, 1.0, named);
    ASSERT_EQ(labelled.tree.lobes.size(), unlabelled.tree.lobes.size());
    double leaf = 0, all = 0;
    for (const Lobe& lobe : labelled.tree.lobes) {
        EXPECT_GE(lobe.leaf_share, 0.0f);
        EXPECT_LE(lobe.leaf_share, 1.0f);
        std::size_t above = 0;
        for (const auto& p : lobe.cluster_points) above += p.z() > 3.8f ? 1 : 0;
        leaf += lobe.leaf_share * static_cast<double>(lobe.points);
        all += static_cast<double>(lobe.points);
        if (lobe.cluster_points.size() == lobe.points) {
            EXPECT_FLOAT_EQ(lobe.leaf_share, static_cast<float>(above) / static_cast<float>(lobe.points));
        }
    }
    EXPECT_NEAR(leaf / all, 0.5, 0.15);
}

// A trunk whose bark is labelled wood keeps it on the main structure where Eq. 1's diameter is
// too small for it: at f_s 0.8 the unlabelled trunk ends 1.8 m up (its bark lies farther from the
// axis than d'), the labelled one reaches the crown, which stays a lobe.
TEST(LobeTree, BarkLabelledWoodKeepsTheTrunkOnTheMainStructure) {
    std::size_t crown = 0;
    PointCloud cloud = trunk_and_crown(&crown);
    auto top = [](const LobeTree& t) {
        float z = 0;
        for (const auto& node : t.skeleton.nodes) z = std::max(z, node.position.z());
        return z;
    };
    const Built unlabelled = build(cloud, 0.8);
    ExtraAttribute& wood = cloud.add_extra("wood", AttributeType::UInt8, 1.0);
    for (std::size_t i = 0; i < cloud.size(); ++i) wood.values[i] = cloud.positions[i].z() > 2.95f ? 0.0 : 1.0;
    LobeOptions named;
    named.leaf_label_attribute = "wood";
    const Built labelled = build(cloud, 0.8, named);
    EXPECT_LT(top(unlabelled.tree), 2.5f);
    EXPECT_GT(top(labelled.tree), 2.8f);
    EXPECT_GT(labelled.report.wood_measured_edges, 0u);
    EXPECT_EQ(unlabelled.report.wood_measured_edges, 0u);
    ASSERT_GE(labelled.tree.lobes.size(), 1u);
    EXPECT_GE(labelled.report.lobe_points, crown * 9 / 10);
    named.wood_measurement.max_factor = 0.5;
    EXPECT_THROW(build(cloud, 0.8, named), Error);
}
