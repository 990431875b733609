// The horizontal centre of a cloud without its outlying parts (geometry/trimmed_centre.hpp).
#include "geometry/trimmed_centre.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace treelobes {
namespace {

// A 9 x 9 grid of points, 0.5 m apart, centred on (2, 3), and `tail` points in a line 6-8 m east of it.
std::vector<Eigen::Vector3f> blob_with_tail(int tail) {
    std::vector<Eigen::Vector3f> points;
    for (int i = -4; i <= 4; ++i)
        for (int j = -4; j <= 4; ++j) points.emplace_back(2.0f + 0.5f * static_cast<float>(i), 3.0f + 0.5f * static_cast<float>(j), 5.0f);
    for (int k = 0; k < tail; ++k) points.emplace_back(8.0f + 2.0f * static_cast<float>(k) / static_cast<float>(tail), 3.0f, 5.0f);
    return points;
}

TEST(TrimmedCentre, AnOutlyingPartDoesNotPullTheCentre) {
    const std::vector<Eigen::Vector3f> points = blob_with_tail(12);  // 12 of 93 points: 13 %
    const Eigen::Vector2d plain = trimmed_centre_xy(points, {.keep = 1.0});
    EXPECT_GT(plain.x(), 2.85);  // the mean is pulled almost 0.9 m east
    const Eigen::Vector2d trimmed = trimmed_centre_xy(points);
    EXPECT_NEAR(trimmed.x(), 2.0, 0.1);
    EXPECT_NEAR(trimmed.y(), 3.0, 1e-9);
}

TEST(TrimmedCentre, ASymmetricCloudKeepsItsCentre) {
    const Eigen::Vector2d centre = trimmed_centre_xy(blob_with_tail(0));
    EXPECT_NEAR(centre.x(), 2.0, 1e-6);
    EXPECT_NEAR(centre.y(), 3.0, 1e-6);
    const std::vector<Eigen::Vector3f> one{{1, 2, 3}};
    EXPECT_TRUE(trimmed_centre_xy(one).isApprox(Eigen::Vector2d(1, 2)));
}

TEST(TrimmedCentre, BadArgumentsAreRefused) {
    EXPECT_THROW(trimmed_centre_xy({}), Error);
    const std::vector<Eigen::Vector3f> points = blob_with_tail(3);
    EXPECT_THROW(trimmed_centre_xy(points, {.keep = 0.0}), Error);
    EXPECT_THROW(trimmed_centre_xy(points, {.keep = 1.5}), Error);
    EXPECT_THROW(trimmed_centre_xy(points, {.rounds = -1}), Error);
    EXPECT_TRUE(trimmed_centre_xy(points, {.rounds = 0}).isApprox(trimmed_centre_xy(points, {.keep = 1.0})));
}

}  // namespace
}  // namespace treelobes
