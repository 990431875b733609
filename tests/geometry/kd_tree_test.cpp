// kd-trees (geometry/kd_tree.hpp) against brute force on random clouds.
#include "geometry/kd_tree.hpp"
#include "support/point_sets.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace treelobes;
using treelobes::test::random_points;

TEST(KdTree, KnnMatchesBruteForce) {
    const auto points = random_points(2000, 1);
    const KdTree tree(points);
    const auto queries = random_points(50, 2);
    std::vector<int> idx;
    std::vector<float> d2;
    for (const auto& q : queries) {
        tree.knn(q, 7, idx, d2);
        std::vector<std::pair<float, int>> all;
        for (std::size_t i = 0; i < points.size(); ++i) all.emplace_back((points[i] - q).squaredNorm(), static_cast<int>(i));
        std::sort(all.begin(), all.end());
        ASSERT_EQ(idx.size(), 7u);
        for (int k = 0; k < 7; ++k) EXPECT_FLOAT_EQ(d2[k], all[k].first);
        EXPECT_EQ(tree.nearest(q), all[0].second);
        tree.radius_search(q, 0.1f, idx, d2);
        const auto inside = std::count_if(all.begin(), all.end(), [](const auto& e) { return e.first < 0.01f; });
        EXPECT_EQ(static_cast<long>(idx.size()), inside);
        EXPECT_TRUE(std::is_sorted(d2.begin(), d2.end()));
    }
}

TEST(KdTree, KnnTableExcludesThePointItselfAndPadsSmallClouds) {
    const std::vector<Eigen::Vector3f> points{{0, 0, 0}, {1, 0, 0}, {3, 0, 0}};
    const KdTree tree(points);
    const KnnTable table = knn_of_all_points(tree, 4);
    EXPECT_EQ(table.row(0)[0], 1);
    EXPECT_EQ(table.row(0)[1], 2);
    EXPECT_EQ(table.row(0)[2], -1);  // only two other points exist
    EXPECT_FLOAT_EQ(table.row_distances(2)[0], 4.0f);
    const KdTree empty(std::vector<Eigen::Vector3f>{});
    EXPECT_EQ(empty.nearest({0, 0, 0}), -1);
}

TEST(GrowingKdTree, NearestMatchesBruteForceWhileGrowing) {
    // Points arrive in batches with queries in between, across several block merges; a
    // duplicate of an early point must resolve to the early one.
    const auto points = random_points(700, 4);
    const auto queries = random_points(20, 5);
    GrowingKdTree tree;
    EXPECT_EQ(tree.nearest({0, 0, 0}), -1);
    std::vector<Eigen::Vector3f> added;
    for (std::size_t i = 0; i < points.size(); ++i) {
        tree.add(points[i]);
        added.push_back(points[i]);
        if (i % 37 != 0) continue;
        for (const auto& q : queries) {
            int brute = 0;
            for (std::size_t j = 1; j < added.size(); ++j)
                if ((added[j] - q).squaredNorm() < (added[brute] - q).squaredNorm()) brute = static_cast<int>(j);
            ASSERT_EQ(tree.nearest(q), brute) << "after " << added.size() << " points";
        }
    }
    tree.add(points[3]);
    EXPECT_EQ(tree.nearest(points[3]), 3);
    EXPECT_EQ(tree.size(), 701u);
    EXPECT_EQ(tree.point(3), points[3]);
}
