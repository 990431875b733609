// point_scatter: mean and (undivided) scatter matrix of a subset of a cloud.
#include "core/error.hpp"
#include "geometry/point_scatter.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <vector>

using namespace treelobes;

TEST(PointScatter, MeanAndScatterOfTheIndexedPointsOnly) {
    // Points 1..4 lie on a line along x through (2, 1, 0); point 0 is far away and not indexed.
    const std::vector<Eigen::Vector3f> points{{100, 100, 100}, {0, 1, 0}, {1, 1, 0}, {3, 1, 0}, {4, 1, 0}};
    const std::vector<int> line{1, 2, 3, 4};
    const PointScatter s = point_scatter(points, line);
    EXPECT_TRUE(s.mean.isApprox(Eigen::Vector3d(2, 1, 0)));
    // Offsets along x: -2, -1, 1, 2 -> sum of squares 10; nothing across.
    Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
    expected(0, 0) = 10;
    EXPECT_TRUE(s.scatter.isApprox(expected));
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(s.scatter);
    EXPECT_NEAR(std::abs(solver.eigenvectors().col(2).x()), 1.0, 1e-12);
}

TEST(PointScatter, NoPointsIsAnInternalError) {
    const std::vector<Eigen::Vector3f> points{{0, 0, 0}};
    try {
        point_scatter(points, std::vector<int>{});
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::Internal);
    }
}
