// `eval skeleton` metrics on hand-made skeletons, TreeQSM tables and point lists.
#include "core/error.hpp"
#include "core/skeleton_io.hpp"
#include "reconstruct/skeleton_eval.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

using namespace treelobes;

namespace {

// Trunk 0 -> (0,0,2) with two 1 m laterals at 1 m; radii 0.1 (trunk) and 0.03 (laterals).
TreeGraph reference_tree(bool with_second_lateral = true) {
    TreeGraph t;
    t.add_node({0, 0, 0}, 0.10f, -1);
    t.add_node({0, 0, 1}, 0.10f, 0);
    t.add_node({0, 0, 2}, 0.08f, 1);
    t.add_node({1, 0, 1}, 0.03f, 1);
    if (with_second_lateral) t.add_node({0, 1, 1}, 0.03f, 1);
    return t;
}

SkeletonGraph write_and_read(const TreeGraph& t, const test::TempDir& dir, const std::string& name) {
    write_skeleton_ply(t, dir / name);
    return read_skeleton_graph(dir / name, "auto");
}

}  // namespace

TEST(SkeletonEval, IdenticalSkeletonsScoreZero) {
    test::TempDir dir;
    const SkeletonGraph a = write_and_read(reference_tree(), dir, "a.ply");
    const SkeletonComparison c = compare_skeletons(a, a);
    EXPECT_LT(c.to_reference.max, 1e-5);
    EXPECT_LT(c.from_reference.p95, 1e-5);
    ASSERT_TRUE(c.length_ratio);
    EXPECT_NEAR(*c.length_ratio, 1.0, 1e-9);
    EXPECT_NEAR(c.length, 4.0, 1e-5);
    EXPECT_EQ(c.components, 1u);
    ASSERT_TRUE(c.trunk_radius_error);
    EXPECT_NEAR(*c.trunk_radius_error, 0.0, 1e-9);
    ASSERT_TRUE(c.branches);
    EXPECT_EQ(c.branches->reference_branches, 3u);
    EXPECT_DOUBLE_EQ(c.branches->recall, 1.0);
    EXPECT_DOUBLE_EQ(c.branches->precision, 1.0);
}

TEST(SkeletonEval, ShiftMissingBranchAndPieces) {
    test::TempDir dir;
    TreeGraph shifted = reference_tree(false);
    for (auto& n : shifted.nodes) n.position.x() += 0.02f;  // 2 cm off everywhere
    const SkeletonGraph ours = write_and_read(shifted, dir, "ours.ply");
    const SkeletonGraph ref = write_and_read(reference_tree(), dir, "ref.ply");
    const SkeletonComparison c = compare_skeletons(ours, ref);
    EXPECT_NEAR(c.to_reference.median, 0.02, 1e-4);
    EXPECT_GT(c.from_reference.max, 0.9);  // the lateral along +y is missing
    ASSERT_TRUE(c.branches);
    EXPECT_NEAR(c.branches->recall, 2.0 / 3.0, 1e-9);
    EXPECT_DOUBLE_EQ(c.branches->precision, 1.0);
    // A forest of two pieces (like a peer's output) is read and counted.
    test::write_text(dir / "pieces.ply",
                     "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                     "element edge 2\nproperty int vertex1\nproperty int vertex2\nend_header\n"
                     "0 0 0\n0 0 1\n0 0 2\n0 0 3\n0 1\n2 3\n");
    const SkeletonGraph pieces = read_skeleton_graph(dir / "pieces.ply");
    EXPECT_EQ(pieces.components(), 2u);
    EXPECT_FALSE(pieces.tree);
    EXPECT_EQ(compare_skeletons(pieces, ref).components, 2u);
}

// A reference branch is scored over its part thicker than min_branch_diameter: a 0.4 m thick
// lateral that tapers into a 1.6 m thin twig counts as detected when its thick part is found,
// and as missed when only the twig is.
TEST(SkeletonEval, BranchRecallScoresTheThickPart) {
    test::TempDir dir;
    // Trunk 0 -> (0,0,4) (the main child at the fork: longer than the lateral) and one lateral
    // from (0,0,1) through `bend` to `tip`.
    const auto tree = [](const Eigen::Vector3f& bend, const Eigen::Vector3f& tip, float bend_radius, float tip_radius) {
        TreeGraph t;
        t.add_node({0, 0, 0}, 0.10f, -1);
        t.add_node({0, 0, 1}, 0.10f, 0);
        t.add_node({0, 0, 4}, 0.08f, 1);
        t.add_node(bend, bend_radius, 1);
        t.add_node(tip, tip_radius, 3);
        return t;
    };
    const SkeletonGraph reference =
            write_and_read(tree({0.4f, 0, 1}, {2.0f, 0, 1}, 0.02f, 0.004f), dir, "ref.ply");  // 4 cm, then an 8 mm twig
    // Ours follows the thick part, then turns up away from the twig: detected (scored over the
    // whole axis it would not be, 0.4 of 2 m matched).
    const SkeletonComparison found =
            compare_skeletons(write_and_read(tree({0.4f, 0, 1}, {0.4f, 0, 2.0f}, 0.02f, 0.01f), dir, "a.ply"), reference);
    ASSERT_TRUE(found.branches);
    EXPECT_EQ(found.branches->reference_branches, 2u);
    EXPECT_DOUBLE_EQ(found.branches->recall, 1.0);
    // Ours goes up and out, missing the thick part, and only meets the twig: missed.
    const SkeletonComparison missed =
            compare_skeletons(write_and_read(tree({0.6f, 0, 1.6f}, {2.0f, 0, 1}, 0.02f, 0.01f), dir, "b.ply"), reference);
    ASSERT_TRUE(missed.branches);
    EXPECT_EQ(missed.branches->reference_branches, 2u);
    EXPECT_DOUBLE_EQ(missed.branches->recall, 0.5);
}

TEST(SkeletonEval, TreeQsmTableAndPointList) {
    test::TempDir dir;
    // Two stem cylinders (order 0) and one branch (order 1), TreeQSM column order.
    test::write_text(dir / "cyl.txt",
                     "0.2\t1.0\t0\t0\t0\t0\t0\t1\t0\t2\t0\t0.2\t1\t0\t1\n"
                     "0.15\t1.0\t0\t0\t1\t0\t0\t1\t1\t0\t0\t0.15\t1\t0\t2\n"
                     "0.05\t0.5\t0\t0\t1\t1\t0\t0\t1\t0\t0\t0.05\t2\t1\t1\n");
    const SkeletonGraph qsm = read_skeleton_graph(dir / "cyl.txt");
    EXPECT_EQ(qsm.kind, "treeqsm");
    EXPECT_NEAR(qsm.total_length(), 2.5, 1e-9);
    ASSERT_EQ(qsm.stem.size(), 4u);  // start and end of each stem cylinder
    EXPECT_DOUBLE_EQ(qsm.stem.front().radius, 0.2);
    EXPECT_DOUBLE_EQ(qsm.stem.back().radius, 0.15);
    EXPECT_EQ(qsm.components(), 1u);

    test::write_text(dir / "ref.txt", "x,y,z\n0,0,0\n0,0,0.5\n0,0,1\n0,0,1.5\n0,0,2\n");
    const SkeletonGraph points = read_skeleton_graph(dir / "ref.txt");
    EXPECT_EQ(points.kind, "points");
    TreeGraph stem;
    stem.add_node({0.01f, 0, 0}, 0.2f, -1);
    stem.add_node({0.01f, 0, 2}, 0.1f, 0);
    const SkeletonGraph ours = write_and_read(stem, dir, "stem.ply");
    const SkeletonComparison c = compare_skeletons(ours, points);
    EXPECT_FALSE(c.reference_length);
    EXPECT_LT(c.to_reference.median, 0.26);  // up to 25 cm from the nearest listed point
    EXPECT_NEAR(c.from_reference.max, 0.01, 1e-4);
    // At 1.3 m: the second stem cylinder (0.15) against our tapering stem (0.2 - 0.65 x 0.1).
    const SkeletonComparison q = compare_skeletons(ours, qsm);
    ASSERT_TRUE(q.reference_trunk_radius && q.trunk_radius && q.trunk_radius_error);
    EXPECT_NEAR(*q.reference_trunk_radius, 0.15, 1e-9);
    EXPECT_NEAR(*q.trunk_radius, 0.135, 1e-6);
    EXPECT_NEAR(*q.trunk_radius_error, -0.1, 1e-5);
}

TEST(SkeletonEval, TrunkRadiiAreComparedAtBreastHeightNotAtTheFlaredBase) {
    test::TempDir dir;
    // Reference: a root flare of 0.3 m narrowing to a 0.15 m trunk from 0.6 m up; ours: a
    // straight 0.15 m trunk whose base lies 0.1 m higher (the scan's stem foot).
    TreeGraph flared;
    flared.add_node({0, 0, 0}, 0.30f, -1);
    flared.add_node({0, 0, 0.6f}, 0.15f, 0);
    flared.add_node({0, 0, 4}, 0.12f, 1);
    TreeGraph straight;
    straight.add_node({0, 0, 0.1f}, 0.15f, -1);
    straight.add_node({0, 0, 4}, 0.15f, 0);
    const SkeletonGraph ref = write_and_read(flared, dir, "flared.ply");
    const SkeletonGraph ours = write_and_read(straight, dir, "straight.ply");
    const SkeletonComparison c = compare_skeletons(ours, ref);
    ASSERT_TRUE(c.trunk_radius_error);
    EXPECT_NEAR(*c.reference_trunk_radius, 0.15 - 0.03 * 0.7 / 3.4, 1e-6);
    EXPECT_NEAR(*c.trunk_radius, 0.15, 1e-6);
    EXPECT_LT(std::abs(*c.trunk_radius_error), 0.05);
    EvalOptions at_base;
    at_base.breast_height = 0;  // the reference's base: its flare, and our lowest radius
    const SkeletonComparison b = compare_skeletons(ours, ref, at_base);
    EXPECT_NEAR(*b.trunk_radius_error, -0.5, 1e-6);
    EvalOptions above;
    above.breast_height = 10;  // above both stems: their top radii
    EXPECT_NEAR(*compare_skeletons(ours, ref, above).trunk_radius_error, 0.15 / 0.12 - 1, 1e-6);
    at_base.breast_height = -1;
    EXPECT_THROW(compare_skeletons(ours, ref, at_base), Error);
}

TEST(SkeletonEval, BadReferencesAreInputErrors) {
    test::TempDir dir;
    test::write_text(dir / "bad.txt", "1 2 3\n4 5\n");
    EXPECT_THROW(read_skeleton_graph(dir / "bad.txt"), Error);
    test::write_text(dir / "nan.txt", "1 2 3\nnan 5 6\n");
    EXPECT_THROW(read_skeleton_graph(dir / "nan.txt"), Error);
    EXPECT_THROW(read_skeleton_graph(dir / "missing.txt"), Error);
    test::write_text(dir / "empty.txt", "");
    EXPECT_THROW(read_skeleton_graph(dir / "empty.txt"), Error);
    EXPECT_THROW(read_skeleton_graph(dir / "bad.txt", "mesh"), Error);
}
