// Disjoint sets (geometry/union_find.hpp).
#include "geometry/union_find.hpp"

#include <gtest/gtest.h>

using namespace treelobes;

TEST(UnionFind, SetsMergeOnceAndTheLargerRootSurvives) {
    UnionFind sets(6);
    EXPECT_TRUE(sets.unite(0, 1));
    EXPECT_TRUE(sets.unite(2, 1));
    EXPECT_FALSE(sets.unite(0, 2));  // already one set
    EXPECT_EQ(sets.set_size(2), 3);
    EXPECT_EQ(sets.find(2), 0);     // {0, 1} was larger than {2}: its root survives
    EXPECT_TRUE(sets.unite(4, 3));  // equal sizes: the smaller index is the root
    EXPECT_EQ(sets.find(4), 3);
    EXPECT_NE(sets.find(5), sets.find(0));
    EXPECT_EQ(sets.set_size(5), 1);
}
