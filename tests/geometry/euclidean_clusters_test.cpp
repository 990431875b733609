// Euclidean clusters (geometry/euclidean_clusters.hpp).
#include "geometry/euclidean_clusters.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace treelobes;

// Two chains of points 4 cm apart, 10 cm between the chains, and a lone point: linked at 5 cm
// they are three clusters in the order of their first points; at 11 cm the chains join.
TEST(EuclideanClusters, ChainsLinkPointByPointAndGapsSeparate) {
    std::vector<Eigen::Vector3f> points;
    for (int k = 0; k < 5; ++k) points.emplace_back(0.04f * static_cast<float>(k), 0, 0);          // 0..4: x 0 .. 0.16
    for (int k = 0; k < 5; ++k) points.emplace_back(0.26f + 0.04f * static_cast<float>(k), 0, 0);  // 5..9
    points.emplace_back(5, 5, 5);                                                                  // 10
    points.emplace_back(0.02f, 0.03f, 0);                                                          // 11: joins the first chain

    const auto clusters = euclidean_clusters(points, 0.05f);
    ASSERT_EQ(clusters.size(), 3u);
    EXPECT_EQ(clusters[0], (std::vector<int>{0, 1, 2, 3, 4, 11}));
    EXPECT_EQ(clusters[1], (std::vector<int>{5, 6, 7, 8, 9}));
    EXPECT_EQ(clusters[2], (std::vector<int>{10}));

    EXPECT_EQ(euclidean_clusters(points, 0.11f).size(), 2u);
    EXPECT_TRUE(euclidean_clusters(std::vector<Eigen::Vector3f>{}, 0.1f).empty());
}
