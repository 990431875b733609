// group_by_internode: points grouped by the internode they belong to, in input order.
#include "reconstruct/internode_points.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace treelobes;

namespace {

std::vector<int> points_of(const InternodePoints& g, std::size_t node) {
    return {g.index.begin() + static_cast<std::ptrdiff_t>(g.start[node]), g.index.begin() + static_cast<std::ptrdiff_t>(g.start[node + 1])};
}

}  // namespace

TEST(InternodePoints, GroupsPointsByInternodeInInputOrder) {
    const std::vector<int> internode{2, 1, 2, 3, 1, 2};
    const InternodePoints g = group_by_internode(internode, 4);
    ASSERT_EQ(g.start.size(), 5u);
    EXPECT_TRUE(points_of(g, 0).empty());
    EXPECT_EQ(points_of(g, 1), (std::vector<int>{1, 4}));
    EXPECT_EQ(points_of(g, 2), (std::vector<int>{0, 2, 5}));
    EXPECT_EQ(points_of(g, 3), (std::vector<int>{3}));
    EXPECT_EQ(g.index.size(), internode.size());
}

TEST(InternodePoints, LeavesOutTheRootAndNodesOutOfRange) {
    // The root (0) has no internode; negative values and values >= nodes belong to none.
    const std::vector<int> internode{0, 1, -1, 4, 7, 1};
    const InternodePoints g = group_by_internode(internode, 4);
    EXPECT_EQ(points_of(g, 1), (std::vector<int>{1, 5}));
    EXPECT_TRUE(points_of(g, 0).empty());
    EXPECT_TRUE(points_of(g, 2).empty());
    EXPECT_TRUE(points_of(g, 3).empty());
    EXPECT_EQ(g.index.size(), 2u);
}

TEST(InternodePoints, EmptyInputGivesEmptyGroups) {
    const InternodePoints g = group_by_internode({}, 3);
    ASSERT_EQ(g.start.size(), 4u);
    for (std::size_t u = 0; u < 3; ++u) EXPECT_TRUE(points_of(g, u).empty());
    EXPECT_TRUE(g.index.empty());
}
