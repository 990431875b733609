// Least-squares cylinders (geometry/cylinder_fit.hpp).
#include "geometry/cylinder_fit.hpp"
#include "support/synthetic_clouds.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace treelobes;

TEST(CylinderFit, RecoversAFullCylinderFromAPoorStart) {
    std::vector<Eigen::Vector3d> points;
    std::mt19937 rng(2);
    std::vector<Eigen::Vector3f> bark;
    test::add_cylinder(bark, {{0.1f, 0.2f, 0.0f}, {0.3f, 0.1f, 0.5f}, 0.04f}, 20000.0f, rng);
    for (const auto& p : bark) points.push_back(p.cast<double>());
    // Started 2 cm off the axis, tilted, with half the radius.
    const CylinderFit fit = fit_cylinder(points, {0.12, 0.21, 0.25}, {0.3, -0.1, 1.0}, 0.02);
    ASSERT_TRUE(fit.converged);
    EXPECT_NEAR(fit.radius, 0.04, 0.001);
    const Eigen::Vector3d axis = Eigen::Vector3d(0.2, -0.1, 0.5).normalized();
    EXPECT_GT(std::abs(fit.direction.dot(axis)), std::cos(0.01));
    const Eigen::Vector3d off = fit.point - Eigen::Vector3d(0.1, 0.2, 0.0);
    EXPECT_LT((off - axis * off.dot(axis)).norm(), 0.001);
    EXPECT_LT(fit.rms, 0.005);
    EXPECT_GT(fit.arc, 340.0);
    EXPECT_FALSE(fit_cylinder(std::vector<Eigen::Vector3d>(points.begin(), points.begin() + 5), {0, 0, 0}, {0, 0, 1}, 0.04).converged);
}
