// Reconstruction of the real scans in ../shared/data (label `real`). Thresholds are the
// accuracy this implementation reaches (see bench/reconstruct_bench.sh for the full
// table) with a margin, so a regression fails the test; the accuracy targets are reported by
// the bench script, not asserted here where they are not met yet.
#include "core/cloud_io.hpp"
#include "reconstruct/reconstruct_tree.hpp"
#include "reconstruct/skeleton_eval.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

using namespace treelobes;

namespace {

struct Scored {
    TreeReconstruction tree;
    SkeletonComparison score;
};

SkeletonGraph as_graph(const TreeGraph& tree) {
    SkeletonGraph g;
    g.kind = "skeleton";
    for (const auto& node : tree.nodes) {
        g.vertices.push_back(tree.origin + node.position.cast<double>());
        g.radius.push_back(node.radius);
    }
    for (std::size_t i = 1; i < tree.size(); ++i) g.edges.emplace_back(tree.nodes[i].parent, static_cast<int>(i));
    g.stem = main_stem(tree);
    g.tree = tree;
    return g;
}

Scored reconstruct_and_score(const std::string& cloud, const std::string& reference) {
    const auto path = test::real_data(cloud);
    const auto ref_path = test::real_data(reference);
    if (path.empty() || ref_path.empty()) return {};
    Scored s;
    s.tree = reconstruct_tree(read_point_cloud(path), {}, cloud);
    s.score = compare_skeletons(as_graph(s.tree.skeleton), read_skeleton_graph(ref_path));
    return s;
}

}  // namespace

TEST(ReconstructReal, WoodskeHs) {
    const Scored s = reconstruct_and_score("woodske/HS_wood.csv", "woodske/HS_reference_skeleton.txt");
    EXPECT_EQ(s.score.components, 1u);
    EXPECT_LT(s.score.to_reference.median, 0.032);
    EXPECT_LT(s.score.to_reference.p95, 0.16);
}

TEST(ReconstructReal, WoodskeOr) {
    const Scored s = reconstruct_and_score("woodske/OR_wood.csv", "woodske/OR_reference_skeleton.txt");
    EXPECT_EQ(s.score.components, 1u);
    EXPECT_LT(s.score.to_reference.median, 0.02);  // the accuracy target
    EXPECT_LT(s.score.to_reference.p95, 0.09);
}

TEST(ReconstructReal, WoodskeSw) {
    const Scored s = reconstruct_and_score("woodske/SW_wood.csv", "woodske/SW_reference_skeleton.txt");
    EXPECT_EQ(s.score.components, 1u);
    EXPECT_LT(s.score.to_reference.median, 0.045);
    EXPECT_LT(s.score.to_reference.p95, 0.189);  // better than the Delaunay+Dijkstra peer
    // From 6.9 m up the 0.5 m stem is scanned only on one side and sparsely (slabs of ~10
    // points): the axis continued from the circle fits below must carry the stem chain to the
    // fork at 8.45 m; the chain used to leave it for the bark at 7.9 m (0.16-0.22 m off).
    ASSERT_FALSE(s.tree.skeleton.empty());
    const SkeletonGraph reference = read_skeleton_graph(test::real_data("woodske/SW_reference_skeleton.txt"));
    std::size_t checked = 0;
    for (int u = 0;; u = s.tree.skeleton.nodes[u].children.front()) {  // the main stem: main child first
        const Eigen::Vector3d p = s.tree.skeleton.origin + s.tree.skeleton.nodes[u].position.cast<double>();
        if (p.z() > 7.0 && p.z() < 8.4) {
            double nearest = 1e9;
            for (const auto& r : reference.vertices) nearest = std::min(nearest, (r - p).norm());
            EXPECT_LT(nearest, 0.1) << "stem node at " << p.z() << " m";
            ++checked;
        }
        if (s.tree.skeleton.nodes[u].children.empty() || p.z() > 8.4) break;
    }
    EXPECT_GE(checked, 8u);
}

TEST(ReconstructReal, ArchiAgainstTreeQsm) {
    const Scored s = reconstruct_and_score("archi/tree1_points.las", "archi/tree1_treeqsm_cylinders.txt");
    EXPECT_EQ(s.score.components, 1u);
    EXPECT_LT(s.score.to_reference.median, 0.051);  // peer: 0.051
    EXPECT_LT(s.score.to_reference.p95, 0.94);      // peer: 0.940
    ASSERT_TRUE(s.score.length_ratio);
    EXPECT_NEAR(*s.score.length_ratio, 1.0, 0.25);  // the accuracy target (peer: 2.24)
    ASSERT_TRUE(s.score.trunk_radius_error);
    EXPECT_LT(std::abs(*s.score.trunk_radius_error), 0.10);  // the accuracy target
}

TEST(ReconstructReal, AdtreeTreesAreTreesAndTheHouseIsNot) {
    for (const char* name : {"tree1.xyz", "tree7.xyz", "tree13.xyz", "Lille_11.xyz", "ahn3_delft.xyz"}) {
        const auto path = test::real_data(std::string("adtree/") + name);
        if (path.empty()) return;
        const TreeReconstruction r = reconstruct_tree(read_point_cloud(path), {}, name);
        EXPECT_FALSE(r.summary.quality.not_a_tree) << name << " planar fraction " << r.summary.quality.planar_fraction;
        r.skeleton.validate(name);
        EXPECT_GT(r.summary.branches, 5u) << name;
    }
    const auto house = test::real_data("adtree/house.xyz");
    if (house.empty()) return;
    EXPECT_TRUE(reconstruct_tree(read_point_cloud(house), {}, "house").summary.quality.not_a_tree);
}

TEST(ReconstructReal, PineWithGround) {
    const auto path = test::real_data("treels/pine.las");
    if (path.empty()) return;
    const TreeReconstruction r = reconstruct_tree(read_point_cloud(path), {}, "pine");
    EXPECT_TRUE(r.summary.ground_removed);
    EXPECT_GT(r.summary.ground_points, 1000u);
    EXPECT_TRUE(r.summary.stem_visible);
    ASSERT_TRUE(r.summary.dbh_fitted);
    EXPECT_GT(r.summary.dbh, 0.15f);  // the stem is about 0.28 m thick at breast height
    EXPECT_LT(r.summary.dbh, 0.40f);
    EXPECT_GT(r.summary.height, 18.0f);
}

// Every LAZ and COPC file under ../shared/data/laz reconstructs from the CLI, whatever its point
// format. laspy's plane.laz is a 2 x 2 m patch of flat ground (4 cm of relief), not a tree: by
// default the ground filter leaves no points and the CLI says so in one line; with the ground
// kept it gives a skeleton flagged not_a_tree.
TEST(ReconstructReal, EveryLazFileReconstructsFromTheCli) {
    const auto root = test::real_data_dir();
    if (root.empty()) return;
    const test::TempDir out;
    int files = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root / "laz")) {
        if (entry.path().extension() != ".laz") continue;
        ++files;
        const std::string stem = test::numbered("run", files);
        const bool ground_only = entry.path().filename() == "plane.laz";
        const auto result = test::run_cli("reconstruct " + test::quoted(entry.path()) + " --out " + test::quoted(out / stem) +
                                          (ground_only ? " --ground keep" : ""));
        EXPECT_EQ(result.exit_code, 0) << entry.path() << ": " << result.err;
        if (!ground_only) continue;
        const auto without_ground =
                test::run_cli("reconstruct " + test::quoted(entry.path()) + " --out " + test::quoted(out / (stem + "g")));
        EXPECT_EQ(without_ground.exit_code, 2);
        EXPECT_NE(without_ground.err.find("too few points left after removing duplicates, outliers and ground"), std::string::npos)
                << without_ground.err;
        std::ifstream summary(out / stem / "plane_summary.json");
        const std::string text{std::istreambuf_iterator<char>(summary), {}};
        EXPECT_NE(text.find("\"not_a_tree\": true"), std::string::npos);
    }
    EXPECT_GE(files, 9);  // MixedConifer, pine, pine_plot and laspy's formats 1, 3, 6, 7, extra bytes, COPC
}
