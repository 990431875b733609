#include "geometry/polyline.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace treelobes;

TEST(Polyline, DistanceToSegmentClampsToTheEnds) {
    const Eigen::Vector3f a(0, 0, 0), b(2, 0, 0);
    EXPECT_FLOAT_EQ(distance_to_segment({1, 0.5f, 0}, a, b), 0.5f);
    EXPECT_FLOAT_EQ(distance_to_segment({-3, 4, 0}, a, b), 5.0f);  // beyond a: distance to a
    EXPECT_FLOAT_EQ(distance_to_segment({5, 0, 4}, a, b), 5.0f);   // beyond b: distance to b
    EXPECT_FLOAT_EQ(distance_to_segment({1, 1, 0}, a, a), std::sqrt(2.0f));
}

// The worst point of each span is kept first: on this zigzag the peak (3), then the valley (2)
// between it and the start; the small wobble (1) is dropped.
TEST(Polyline, DouglasPeuckerKeepsTheBendsAndIsAFixedPoint) {
    const std::vector<Eigen::Vector3f> points{{0, 0, 0}, {1, 0.05f, 0}, {2, 0, 0}, {3, 1, 0}, {4, 0, 0}};
    const auto deviation_of = [](const std::vector<Eigen::Vector3f>& p) {
        return [&p](std::size_t a, std::size_t b, std::size_t k) { return distance_to_segment(p[k], p[a], p[b]); };
    };
    const std::vector<char> keep = douglas_peucker(points.size(), 0.1f, deviation_of(points));
    EXPECT_EQ(keep, (std::vector<char>{1, 0, 1, 1, 1}));
    std::vector<Eigen::Vector3f> kept;
    for (std::size_t k = 0; k < points.size(); ++k)
        if (keep[k]) kept.push_back(points[k]);
    EXPECT_EQ(douglas_peucker(kept.size(), 0.1f, deviation_of(kept)), std::vector<char>(kept.size(), 1));
    EXPECT_EQ(douglas_peucker(points.size(), 2.0f, deviation_of(points)), (std::vector<char>{1, 0, 0, 0, 1}));
    EXPECT_TRUE(douglas_peucker(0, 0.1f, deviation_of(points)).empty());
    EXPECT_EQ(douglas_peucker(1, 0.1f, deviation_of(points)), std::vector<char>{1});
}
