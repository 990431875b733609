#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/tree_graph.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

using namespace treelobes;

namespace {

// Trunk 0-1-2 (2 m), a lateral 1-3-4 (1 m + 1 m) and a short twig 2-5 (0.5 m).
TreeGraph small_tree() {
    TreeGraph tree;
    tree.add_node({0, 0, 0}, 0.3f, -1);
    tree.add_node({0, 0, 1}, 0.2f, 0);
    tree.add_node({0, 0, 2}, 0.1f, 1);
    tree.add_node({1, 0, 1}, 0.1f, 1);
    tree.add_node({2, 0, 1}, 0.05f, 3);
    tree.add_node({0, 0.5f, 2}, 0.02f, 2);
    return tree;
}

}  // namespace

TEST(TreeGraph, SubtreeLengthsAndTotals) {
    const TreeGraph tree = small_tree();
    const auto length = tree.subtree_lengths();
    EXPECT_FLOAT_EQ(length[0], 4.5f);
    EXPECT_FLOAT_EQ(length[1], 3.5f);
    EXPECT_FLOAT_EQ(length[3], 1.0f);
    EXPECT_FLOAT_EQ(length[4], 0.0f);
    EXPECT_FLOAT_EQ(tree.total_length(), 4.5f);
    EXPECT_EQ(tree.tip_count(), 2u);
}

TEST(TreeGraph, PreorderFollowsMainChildFirst) {
    TreeGraph tree = small_tree();
    EXPECT_EQ(tree.preorder(), (std::vector<int>{0, 1, 2, 5, 3, 4}));
    // The lateral 3-4 (2 m with its edge) outweighs the trunk top 2-5 (1.5 m): it becomes main.
    tree.order_children_by_subtree_length();
    EXPECT_EQ(tree.nodes[1].children, (std::vector<int>{3, 2}));
    EXPECT_EQ(tree.preorder(), (std::vector<int>{0, 1, 3, 4, 2, 5}));
    const auto order = tree.branch_orders();
    EXPECT_EQ(order[4], 0);
    EXPECT_EQ(order[2], 1);
    EXPECT_EQ(order[5], 1);
}

TEST(TreeGraph, ValidateRejectsBrokenLinks) {
    TreeGraph tree = small_tree();
    EXPECT_NO_THROW(tree.validate("t"));
    tree.nodes[4].parent = 2;  // child list of 3 still names 4
    EXPECT_THROW(tree.validate("t"), Error);
    TreeGraph nan_tree = small_tree();
    nan_tree.nodes[2].position.x() = std::nanf("");
    EXPECT_THROW(nan_tree.validate("t"), Error);
    EXPECT_THROW(TreeGraph().validate("t"), Error);
}

TEST(TreeGraph, KeepNodesReattachesToTheNearestKeptAncestor) {
    const TreeGraph tree = small_tree();
    std::vector<int> new_index;
    // Drop node 1 (the fork) and the twig tip 5: 2 and 3 hang from the root now.
    const TreeGraph kept = keep_nodes(tree, {true, false, true, true, true, false}, new_index);
    ASSERT_EQ(kept.size(), 4u);
    EXPECT_EQ(new_index, (std::vector<int>{0, 0, 1, 2, 3, 1}));
    EXPECT_EQ(kept.nodes[1].parent, 0);
    EXPECT_EQ(kept.nodes[2].parent, 0);
    EXPECT_EQ(kept.nodes[3].parent, 2);
    EXPECT_FLOAT_EQ(kept.nodes[3].radius, 0.05f);
    EXPECT_NO_THROW(kept.validate("kept"));
    EXPECT_THROW(keep_nodes(tree, {false, true, true, true, true, true}, new_index), Error);  // the root must stay
}

TEST(TreeGraph, ChainsRunBetweenForksAndTips) {
    const auto chains = tree_chains(small_tree());
    // From the root to the fork 1, then from 1 along the trunk to the tip 5 and along the lateral.
    ASSERT_EQ(chains.size(), 3u);
    EXPECT_EQ(chains[0], (std::vector<int>{0, 1}));
    EXPECT_EQ(chains[1], (std::vector<int>{1, 2, 5}));
    EXPECT_EQ(chains[2], (std::vector<int>{1, 3, 4}));
}

TEST(AtomicFile, FailureKeepsThePreviousFileAndLeavesNoTemporary) {
    test::TempDir dir;
    write_file_atomically(dir / "out.txt", "old");
    EXPECT_THROW(write_atomically(dir / "out.txt",
                                  [](std::ostream& out) {
                                      out << "half-written";
                                      throw Error::input("x", "simulated failure");
                                  }),
                 Error);
    EXPECT_EQ(read_file(dir / "out.txt"), "old");
    int files = 0;
    for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) ++files;
    EXPECT_EQ(files, 1);
}
