// TreeGraph -> bracketed string: the turtle draws it back into the same tree, and the chain of a
// skeleton reproduces it like that of an L-system.
#include "lsystem/lsystem.hpp"
#include "lsystem/multires_chain.hpp"
#include "lsystem/tree_string.hpp"
#include "lsystem_test_util.hpp"

#include <gtest/gtest.h>

using namespace treelobes;
using namespace treelobes::lsystem;
using namespace treelobes::lsystem::test_util;

namespace {

// Same shape, node for node in pre-order (main child first), radii exactly, positions to `tolerance`.
void expect_same_tree(const TreeGraph& a, const TreeGraph& b, float tolerance) {
    const std::vector<int> pa = a.preorder(), pb = b.preorder();
    ASSERT_EQ(pa.size(), pb.size());
    for (std::size_t i = 0; i < pa.size(); ++i) {
        const TreeNode& x = a.nodes[static_cast<std::size_t>(pa[i])];
        const TreeNode& y = b.nodes[static_cast<std::size_t>(pb[i])];
        ASSERT_EQ(x.children.size(), y.children.size()) << "pre-order position " << i;
        EXPECT_LE((x.position - y.position).norm(), tolerance) << "pre-order position " << i;
        EXPECT_EQ(x.radius, y.radius) << "pre-order position " << i;
    }
}

TreeGraph sample_tree() {
    const LSystem s = load_lsystem(example("abop_ternary_tropism.lsys"));
    TreeGraph tree = interpret(derive(s, {4, std::nullopt}), s.turtle).tree;
    // A reconstructed skeleton: tapering radii, the root off the origin, a zero-length internode.
    for (std::size_t i = 0; i < tree.size(); ++i) {
        tree.nodes[i].radius = 0.3f / (1.0f + static_cast<float>(i));
        tree.nodes[i].position += Eigen::Vector3f(10.5f, -3.25f, 100.0f);
    }
    const int last = static_cast<int>(tree.size()) - 1;
    tree.add_node(tree.nodes[static_cast<std::size_t>(last)].position, 0.001f, last);
    return tree;
}

}  // namespace

TEST(TreeString, RoundTripGivesTheSameTree) {
    const TreeGraph tree = sample_tree();
    const TreeString converted = tree_to_module_string(tree);
    EXPECT_EQ(converted.modules.count("F"), tree.size() - 1);
    const TurtleResult back = interpret(converted.modules, converted.turtle);
    back.tree.validate("round trip");
    expect_same_tree(tree, back.tree, 2e-5f);
    EXPECT_EQ(back.tree.nodes[0].radius, tree.nodes[0].radius);
}

TEST(TreeString, SmallTreeTextIsBracketed) {
    TreeGraph t;
    t.add_node({0, 0, 0}, 0.5f, -1);
    t.add_node({0, 0, 1}, 0.25f, 0);
    t.add_node({1, 0, 1}, 0.125f, 1);  // lateral (second child)
    t.add_node({0, 0, 2}, 0.25f, 1);
    std::swap(t.nodes[1].children[0], t.nodes[1].children[1]);  // main child (3) first
    const TreeString s = tree_to_module_string(t);
    EXPECT_EQ(s.modules.to_string(), "!(0.5)SetHead(0,0,1)F(1)[!(0.25)SetHead(1,0,0)F(1)]!(0.5)SetHead(0,0,1)F(1)");
    EXPECT_EQ(s.turtle.root_width, 1.0);
}

TEST(TreeString, SkeletonChainReproducesTheSkeleton) {
    const TreeGraph tree = sample_tree();
    const TreeString converted = tree_to_module_string(tree);
    const TurtleResult direct = interpret(converted.modules, converted.turtle);
    const MultiresChain chain = build_multires_chain(converted.modules);
    // One LOD per tip of the skeleton; the full chain is the converted tree exactly.
    EXPECT_EQ(chain.lod_count(), tree.tip_count());
    EXPECT_EQ(edges(extract_lod(chain, chain.lod_count() - 1, converted.turtle).tree), edges(direct.tree));
    // The chain's lengths are the skeleton's: LOD 0 follows the longest subtree from the root.
    EXPECT_NEAR(chain.tadt.nodes[0].subtree_length, tree.total_length(), 1e-3);
}
