// Least-squares and RANSAC circles (geometry/ransac_fit.hpp).
#include "geometry/ransac_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

using namespace treelobes;

TEST(CircleFit, LeastSquaresRecoversANoisyArcAndRefusesDegenerateInput) {
    // A half circle (a one-sided scan of a stem) of radius 0.2 m around (1, -2) with 2 mm noise.
    std::mt19937 random(3);
    std::normal_distribution<double> noise(0.0, 0.002);
    std::vector<Eigen::Vector2d> arc;
    for (int i = 0; i < 200; ++i) {
        const double angle = std::numbers::pi * i / 199.0;
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const double y = -2 + 0.2 * std::sin(angle) + noise(random), x = 1 + 0.2 * std::cos(angle) + noise(random);
        arc.push_back(Eigen::Vector2d(x, y));
    }
    const auto circle = fit_circle_least_squares(arc);
    ASSERT_TRUE(circle.has_value());
    EXPECT_NEAR(circle->radius, 0.2, 0.005);
    EXPECT_NEAR(circle->centre.x(), 1.0, 0.005);
    EXPECT_NEAR(circle->centre.y(), -2.0, 0.005);

    const std::vector<Eigen::Vector2d> two{{0, 0}, {1, 0}};
    EXPECT_FALSE(fit_circle_least_squares(two).has_value());
    const std::vector<Eigen::Vector2d> same(10, Eigen::Vector2d(0.5, 0.5));
    EXPECT_FALSE(fit_circle_least_squares(same).has_value());
    const std::vector<Eigen::Vector2d> line{{0, 0}, {1, 1}, {2, 2}, {3, 3}};
    EXPECT_FALSE(fit_circle_least_squares(line).has_value());
}

TEST(CircleFit, RansacIgnoresOutliersAndReportsCoverage) {
    // A full ring of radius 0.15 m around (0.5, 0.5) plus 40 % scattered points inside it.
    std::mt19937 random(7);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<Eigen::Vector2f> points;
    for (int i = 0; i < 300; ++i) {
        const float angle = 2.0f * std::numbers::pi_v<float> * unit(random);
        points.emplace_back(0.5f + 0.15f * std::cos(angle), 0.5f + 0.15f * std::sin(angle));
    }
    // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
    // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
    for (int i = 0; i < 200; ++i) {
        const float y = 0.4f + 0.2f * unit(random), x = 0.4f + 0.2f * unit(random);
        points.emplace_back(x, y);
    }
    const CircleFit fit = fit_circle(points, 0.01f, 0.05f, 0.5f);
    ASSERT_TRUE(fit.ok);
    EXPECT_NEAR(fit.radius, 0.15f, 0.003f);
    EXPECT_NEAR(fit.centre.x(), 0.5f, 0.003f);
    EXPECT_NEAR(fit.centre.y(), 0.5f, 0.003f);
    EXPECT_GE(fit.inliers, 300u);
    EXPECT_GT(fit.coverage, 0.9f);
    EXPECT_FALSE(fit_circle(std::vector<Eigen::Vector2f>(points.begin(), points.begin() + 4), 0.01f, 0.05f, 0.5f).ok);
}

TEST(HeightPlane, LeastSquaresRecoversASlopeAndRefusesALine) {
    // DTM heights under a trunk seen from one side: a 20-degree slope z = 2 + 0.364 x - 0.1 y,
    // sampled only on the half x < 0 of a disc.
    std::vector<Eigen::Vector3d> half;
    for (double x = -0.8; x <= 0.0; x += 0.1)
        for (double y = -0.8; y <= 0.8; y += 0.1) half.emplace_back(x, y, 2.0 + 0.364 * x - 0.1 * y);
    const auto plane = fit_height_plane_least_squares(half);
    ASSERT_TRUE(plane.has_value());
    EXPECT_NEAR((*plane)(0), 2.0, 1e-9);  // the height at (0, 0), outside the samples
    EXPECT_NEAR((*plane)(1), 0.364, 1e-9);
    EXPECT_NEAR((*plane)(2), -0.1, 1e-9);
    std::vector<Eigen::Vector3d> line;
    for (double t = 0.0; t < 1.0; t += 0.1) line.emplace_back(t, 2.0 * t, 1.0 + t);
    EXPECT_FALSE(fit_height_plane_least_squares(line).has_value());
    EXPECT_FALSE(fit_height_plane_least_squares(std::vector<Eigen::Vector3d>(half.begin(), half.begin() + 2)).has_value());
}
