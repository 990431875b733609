// Local (density-ratio) outlier test of reconstruct/preprocess against the global one, on a
// scan shaped like a leafy TLS crown: a densely sampled stem and a thin branch seen only as a
// sparse run of samples (occluded, far from the scanner), plus stray returns in the air.
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "reconstruct/preprocess.hpp"
#include "reconstruct/reconstruct_tree.hpp"
#include "support/synthetic_clouds.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <random>

using namespace treelobes;

namespace {

// Stem 0..3 m (r 10 cm, ~1.3 cm sampling) and a 1 cm branch from the stem at 1.5 m out to
// (1.2, 0, 2.3), sampled every ~3 cm on its upper side; three stray points 0.4-0.8 m from
// anything. Branch points are numbered [branch_begin, branch_end).
struct SparseBranchScan {
    PointCloud cloud;
    std::size_t branch_begin = 0, branch_end = 0;
    test::Segment branch{{0.1f, 0, 1.5f}, {1.2f, 0, 2.3f}, 0.01f};
    SparseBranchScan() {
        std::mt19937 rng(11);
        test::add_cylinder(cloud.positions, {{0, 0, 0}, {0, 0, 3}, 0.10f}, 6000.0f, rng);
        branch_begin = cloud.positions.size();
        const Eigen::Vector3f axis = branch.b - branch.a;
        const int samples = static_cast<int>(axis.norm() / 0.03f);
        std::uniform_real_distribution<float> jitter(-0.004f, 0.004f);
        for (int i = 0; i <= samples; ++i) {
            const float t = static_cast<float>(i) / static_cast<float>(samples);
            // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
            // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
            const float z = 0.01f + jitter(rng), y = jitter(rng), x = jitter(rng);
            cloud.positions.push_back(branch.a + t * axis + Eigen::Vector3f(x, y, z));
        }
        branch_end = cloud.positions.size();
        cloud.positions.push_back({-0.8f, 0.5f, 2.0f});
        cloud.positions.push_back({0.5f, -0.6f, 1.0f});
        cloud.positions.push_back({-0.4f, -0.4f, 3.4f});
    }
    std::size_t kept_branch_points(const Preprocessed& p) const {
        std::size_t kept = 0;
        for (std::size_t i = branch_begin; i < branch_end; ++i) kept += p.point_of_input[i] >= 0;
        return kept;
    }
};

PreprocessOptions keep_ground(OutlierTest test) {
    PreprocessOptions o;
    o.ground = GroundMode::Keep;
    o.outlier_test = test;
    return o;
}

// Largest distance from the branch's axis, over its outer 80 %, to the nearest skeleton node.
float worst_branch_gap(const TreeGraph& tree, const test::Segment& branch) {
    float worst = 0;
    for (float t = 0.2f; t <= 1.0f; t += 0.05f) {
        const Eigen::Vector3f p = branch.a + t * (branch.b - branch.a);
        float best = 1e9f;
        for (const auto& node : tree.nodes) best = std::min(best, (node.position - p).norm());
        worst = std::max(worst, best);
    }
    return worst;
}

}  // namespace

TEST(Outliers, LocalTestKeepsASparseBranchTheGlobalTestCutsAway) {
    const SparseBranchScan scan;
    const std::size_t branch = scan.branch_end - scan.branch_begin;
    const Preprocessed global = preprocess_cloud(scan.cloud, keep_ground(OutlierTest::Global));
    const Preprocessed local = preprocess_cloud(scan.cloud, keep_ground(OutlierTest::Local));
    EXPECT_FALSE(global.local_outlier_test);
    EXPECT_TRUE(local.local_outlier_test);
    EXPECT_LT(scan.kept_branch_points(global), branch / 2) << "the global test no longer removes the sparse branch";
    EXPECT_GE(scan.kept_branch_points(local), branch - 2) << "the local test removed samples of the branch";
    for (std::size_t i = scan.branch_end; i < scan.cloud.size(); ++i) {
        EXPECT_EQ(global.point_of_input[i], -1) << "stray point " << i;
        EXPECT_EQ(local.point_of_input[i], -1) << "stray point " << i;
    }
    EXPECT_LT(local.outliers, 20u);  // the stem's samples are as dense as their neighbours
}

TEST(Outliers, SkeletonFollowsTheSparseBranchOnlyWithTheLocalTest) {
    const SparseBranchScan scan;
    ReconstructOptions global, local;
    global.preprocess.outlier_test = OutlierTest::Global;
    local.preprocess.outlier_test = OutlierTest::Local;
    const TreeReconstruction without = reconstruct_tree(scan.cloud, global, "sparse branch");
    const TreeReconstruction with = reconstruct_tree(scan.cloud, local, "sparse branch");
    EXPECT_LT(worst_branch_gap(with.skeleton, scan.branch), 0.05f);
    EXPECT_GT(worst_branch_gap(without.skeleton, scan.branch), 0.3f);
    // Same input and options: the same skeleton.
    const TreeReconstruction again = reconstruct_tree(scan.cloud, local, "sparse branch");
    ASSERT_EQ(again.skeleton.size(), with.skeleton.size());
    for (std::size_t u = 0; u < with.skeleton.size(); ++u) EXPECT_EQ(again.skeleton.nodes[u].position, with.skeleton.nodes[u].position);
}

// The ground is not the tree: a terrestrial scan samples the ground near the scanner far more
// densely than a crown, and with the ground in the outlier statistics the demo's leaf-off sample
// lost 389 of its 2,900 tree points, the sparse twigs of its top among them (the skeleton ended
// 1.2 m low). The same tree points are outliers with the ground in the scan or cut out before.
TEST(Outliers, TheGroundDoesNotSetTheTreesOutlierLimit) {
    const PointCloud scan = read_point_cloud(test::source_dir() / "data/synthetic/ailanthus_altissima_5.las");
    PointCloud tree;
    float top = -1e9f;
    for (std::size_t i = 0; i < scan.size(); ++i)
        if (scan.classification[i] != kAsprsGround) {
            tree.positions.push_back(scan.positions[i]);
            top = std::max(top, scan.positions[i].z());
        }
    tree.origin = scan.origin;
    const Preprocessed with_ground = preprocess_cloud(scan, PreprocessOptions{}, "with ground");
    const Preprocessed without = preprocess_cloud(tree, PreprocessOptions{}, "without");
    ASSERT_TRUE(with_ground.ground_found);
    EXPECT_GT(with_ground.ground, scan.size() / 2);
    EXPECT_NEAR(static_cast<double>(with_ground.outliers), static_cast<double>(without.outliers), 0.01 * tree.size());
    EXPECT_LT(with_ground.outliers, tree.size() / 20);
    float kept_top = -1e9f;
    for (const auto& p : with_ground.points) kept_top = std::max(kept_top, p.z());
    EXPECT_GT(kept_top, top - 0.5f);
}

TEST(Outliers, RejectsBadOptions) {
    const SparseBranchScan scan;
    PreprocessOptions o = keep_ground(OutlierTest::Local);
    o.outlier_ratio = 0.0f;
    EXPECT_EQ(test::error_code_of([&] { preprocess_cloud(scan.cloud, o); }), ExitCode::Usage);
    o = keep_ground(OutlierTest::Auto);
    o.leafy_linear_fraction = 1.5f;
    EXPECT_EQ(test::error_code_of([&] { preprocess_cloud(scan.cloud, o); }), ExitCode::Usage);
    EXPECT_EQ(test::error_code_of([] { parse_outlier_test("sometimes"); }), ExitCode::Usage);
}

TEST(Outliers, CliOptionReachesTheFilter) {
    const test::TempDir dir;
    const SparseBranchScan scan;
    write_point_cloud(scan.cloud, dir / "scan.xyz");
    auto outliers = [&](const std::string& options, const std::string& out) {
        const auto r = test::run_cli("reconstruct " + test::quoted(dir / "scan.xyz") + " --out " + test::quoted(dir / out) + options);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        std::ifstream in(dir / out / "scan_summary.json");
        const auto summary = nlohmann::json::parse(in);
        EXPECT_EQ(summary["points"]["outlier_test"].get<std::string>(), options.substr(options.rfind(' ') + 1));
        return summary["points"]["outliers"].get<std::size_t>();
    };
    const std::size_t global = outliers(" --outlier-test global", "global"), local = outliers(" --outlier-test local", "local");
    EXPECT_GT(global, local + 20) << "the sparse branch was not kept through the CLI";
    EXPECT_EQ(test::run_cli("reconstruct " + test::quoted(dir / "scan.xyz") + " --out " + test::quoted(dir / "bad") +
                            " --outlier-test sometimes")
                      .exit_code,
              1);
}

namespace {

// A small tree of thin, sparsely scanned branches (3 cm stem, sixteen 1 cm branches), optionally
// inside a crown of leaf clutter: 8000 blades of four returns each (4 cm plates at random
// orientations) in a ball of 0.9 m, as a TLS scan samples a leafy crown.
PointCloud thin_tree(bool leaves) {
    std::vector<test::Segment> wood{{{0, 0, 0}, {0, 0, 2.5f}, 0.03f}};
    for (int b = 0; b < 16; ++b) {
        const float a = 0.3927f * static_cast<float>(b), z = 1.6f + 0.05f * static_cast<float>(b);
        wood.push_back({{0, 0, z}, {std::cos(a), std::sin(a), z + 0.5f}, 0.01f});
    }
    PointCloud cloud = test::cloud_from(wood, 800.0f, 5);
    if (!leaves) return cloud;
    std::mt19937 rng(6);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    for (int blade = 0; blade < 8000; ++blade) {
        Eigen::Vector3f c, n;
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const auto draw = [&] {
            const float z = unit(rng), y = unit(rng), x = unit(rng);
            return Eigen::Vector3f(x, y, z);
        };
        do c = draw();
        while (c.norm() > 1.0f);
        do n = draw();
        while (n.norm() > 1.0f || n.norm() < 0.1f);
        const Eigen::Vector3f u = n.unitOrthogonal(), v = n.normalized().cross(u);
        for (int k = 0; k < 4; ++k) {
            const float along_v = unit(rng), along_u = unit(rng);  // GCC's order within the sum
            cloud.positions.push_back(Eigen::Vector3f(0, 0, 2.5f) + 0.9f * c + 0.02f * (along_u * u + along_v * v));
        }
    }
    return cloud;
}

}  // namespace

TEST(Outliers, AutoTestPicksTheLocalTestForLeafyCrownsOnly) {
    PreprocessOptions o;
    o.ground = GroundMode::Keep;
    const Preprocessed leafy = preprocess_cloud(thin_tree(true), o);
    const Preprocessed bare = preprocess_cloud(thin_tree(false), o);
    EXPECT_TRUE(leafy.local_outlier_test) << "linear fraction " << leafy.linear_fraction;
    EXPECT_FALSE(bare.local_outlier_test) << "linear fraction " << bare.linear_fraction;
    EXPECT_LT(leafy.linear_fraction, 0.09f);
    EXPECT_GT(bare.linear_fraction, 0.2f);
    // Planes (walls of a shed) have few linear neighbourhoods too, but are no crown.
    PointCloud shed;
    for (float a = 0; a <= 4; a += 0.04f)
        for (float z = 0; z <= 3; z += 0.04f) {
            shed.positions.push_back({a, 0, z});
            shed.positions.push_back({0, a, z});
        }
    const Preprocessed walls = preprocess_cloud(shed, o);
    EXPECT_FALSE(walls.local_outlier_test);
    EXPECT_LT(walls.linear_fraction, 0.09f);
}

TEST(Outliers, NeighbourhoodShapesFromTheKnnTableMatchKdTreeQueries) {
    // With a table handed on (as reconstruct and classify ask for) the gate reads the outlier
    // query's rows instead of querying again: the same neighbourhoods, so the same fractions.
    PreprocessOptions queries;
    queries.ground = GroundMode::Keep;
    PreprocessOptions table = queries;
    table.table_width = 20;
    for (bool leaves : {true, false}) {
        const PointCloud cloud = thin_tree(leaves);
        const Preprocessed a = preprocess_cloud(cloud, queries), b = preprocess_cloud(cloud, table);
        EXPECT_GT(a.linear_fraction, 0.0f);
        EXPECT_EQ(a.linear_fraction, b.linear_fraction) << (leaves ? "leafy" : "bare");
        EXPECT_EQ(a.local_outlier_test, b.local_outlier_test);
    }
}
