// The part of a reference skeleton a scan sees: hit internodes and their way to the root.
#include "core/error.hpp"
#include "reconstruct/visible_reference.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace treelobes {
namespace {

// 0 -> 1 -> 2 (trunk), 1 -> 3 -> 4 (a branch), 0 -> 5 (a twig)
SkeletonGraph y_reference() {
    TreeGraph tree;
    tree.add_node({0, 0, 0}, 0.2f, -1);
    tree.add_node({0, 0, 1}, 0.15f, 0);
    tree.add_node({0, 0, 2}, 0.1f, 1);
    tree.add_node({1, 0, 2}, 0.05f, 1);
    tree.add_node({2, 0, 3}, 0.02f, 3);
    tree.add_node({0, 1, 0.5f}, 0.01f, 0);
    SkeletonGraph g;
    g.kind = "skeleton";
    for (const auto& n : tree.nodes) {
        g.vertices.push_back(n.position.cast<double>());
        g.radius.push_back(n.radius);
        if (n.parent >= 0) g.edges.emplace_back(n.parent, static_cast<int>(g.vertices.size() - 1));
    }
    g.stem = main_stem(tree);
    g.tree = tree;
    return g;
}

TEST(VisibleReference, KeepsSeenInternodesAndTheirWayToTheRoot) {
    // Internode 4 (the branch tip) seen by 3 points, the trunk's 2 by 1 point, the twig 5 by none.
    const std::vector<double> labels{4, 4, 4, 2, -1, -1};
    const SkeletonGraph visible = visible_reference(y_reference(), labels, 2);
    ASSERT_TRUE(visible.tree);
    EXPECT_EQ(visible.vertices.size(), 4u);  // 0, 1, 3, 4
    EXPECT_EQ(visible.edges.size(), 3u);
    EXPECT_NEAR(visible.total_length(), 1.0 + 2.0 * std::sqrt(2.0), 1e-6);
    EXPECT_EQ(visible.tree->tip_count(), 1u);
    EXPECT_FLOAT_EQ(visible.radius[0], 0.2f);
    EXPECT_EQ(visible.stem.size(), 3u);  // the whole trunk, seen or not: its radius is compared at breast height
    EXPECT_EQ(visible_reference(y_reference(), labels, 1).vertices.size(), 5u);  // the trunk tip too
}

// The skeleton's side against what the scan touched, the reference's against what it saw well: a
// skeleton that follows a twig of two returns is not wrong there, nor is a skeleton without it
// penalised.
TEST(VisibleReference, EachSideIsScoredAgainstItsOwnPart) {
    const std::vector<double> labels{4, 4, 4, 4, 4, 2, 2, 2, 2, 2, 5, 5};  // twig 5 touched by 2 points
    const SkeletonGraph reference = y_reference();
    const SkeletonComparison both = compare_with_visible_part(reference, reference, labels, 5);
    const SkeletonComparison seen_only = compare_skeletons(reference, visible_reference(reference, labels, 5));
    EXPECT_GT(seen_only.to_reference.max, 0.5);  // the twig lies away from the well-seen part
    EXPECT_NEAR(both.to_reference.max, 0.0, 1e-6);
    EXPECT_EQ(both.from_reference.samples, seen_only.from_reference.samples);
    ASSERT_TRUE(both.branches && seen_only.branches);
    EXPECT_DOUBLE_EQ(both.branches->precision, 1.0);
    EXPECT_LT(seen_only.branches->precision, 1.0);
    EXPECT_EQ(both.branches->reference_branches, seen_only.branches->reference_branches);
    EXPECT_NEAR(*both.reference_length, *seen_only.reference_length, 1e-9);
    EXPECT_NEAR(*both.touched_reference_length, reference.total_length(), 1e-6);
}

TEST(VisibleReference, NothingSeenOrNotATreeIsAnError) {
    EXPECT_THROW(visible_reference(y_reference(), std::vector<double>{-1, 9}, 1), Error);
    SkeletonGraph points = y_reference();
    points.tree.reset();
    EXPECT_THROW(visible_reference(points, std::vector<double>{4}, 1), Error);
}

}  // namespace
}  // namespace treelobes
