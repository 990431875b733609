// Convex hulls: closed and outward, the right volume, and the same bytes whatever the order of the
// points and wherever CGAL's handles land in memory (planar facets with more than three corners).
#include "core/random.hpp"
#include "geometry/convex_hull.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <vector>

using namespace treelobes;

namespace {

// A unit cube's corners, its face and edge midpoints and its centre: six square facets whose
// diagonals CGAL may choose either way, and points on facets and edges that are not corners.
std::vector<Eigen::Vector3f> cube_with_midpoints() {
    std::vector<Eigen::Vector3f> points;
    for (int x = 0; x <= 2; ++x)
        for (int y = 0; y <= 2; ++y)
            for (int z = 0; z <= 2; ++z) points.emplace_back(0.5f * x, 0.5f * y, 0.5f * z);
    return points;
}

bool same_mesh(const TriangleMesh& a, const TriangleMesh& b) { return a.vertices == b.vertices && a.faces == b.faces; }

}  // namespace

TEST(ConvexHull, CubeIsClosedOutwardAndHasOnlyItsCorners) {
    const TriangleMesh hull = convex_hull(cube_with_midpoints(), {10, 20, 30});
    EXPECT_EQ(hull.origin, Eigen::Vector3d(10, 20, 30));
    EXPECT_EQ(hull.vertices.size(), 8u);  // midpoints are not corners
    EXPECT_EQ(hull.faces.size(), 12u);    // two triangles a square
    EXPECT_NEAR(hull.signed_volume(), 1.0, 1e-9);
    EXPECT_NEAR(hull.area(), 6.0, 1e-9);
    std::map<std::pair<int, int>, int> directed;
    for (const auto& f : hull.faces)
        for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
    for (const auto& [edge, count] : directed) {
        EXPECT_EQ(count, 1);
        EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << "open at " << edge.first << "-" << edge.second;
    }
}

TEST(ConvexHull, SameBytesForAnyPointOrderAndHeapLayout) {
    const std::vector<Eigen::Vector3f> points = cube_with_midpoints();
    const TriangleMesh first = convex_hull(points, {});
    Rng rng(7);
    std::vector<std::vector<char>> heap_noise;
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<Eigen::Vector3f> shuffled = points;
        for (std::size_t k = shuffled.size() - 1; k > 0; --k) std::swap(shuffled[k], shuffled[rng.next() % (k + 1)]);
        heap_noise.emplace_back(1 + rng.next() % 97);
        ASSERT_TRUE(same_mesh(first, convex_hull(shuffled, {}))) << "trial " << trial;
    }
}

TEST(ConvexHull, FlatOrTooFewPointsGiveAnEmptyMesh) {
    EXPECT_TRUE(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {}).faces.empty());
    EXPECT_TRUE(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5f, 0.5f, 0}}, {}).faces.empty());
}

TEST(ProjectedHull, AreaOfASquareSeenFromAboveAndItsEqualAreaDiameter) {
    const std::vector<Eigen::Vector3f> points{{0, 0, 1}, {2, 0, 3}, {2, 2, 0}, {0, 2, 5}, {1, 1, 9}};
    EXPECT_NEAR(ring_area(projected_hull(points)), 4.0, 1e-9);
    EXPECT_NEAR(equal_area_diameter(std::numbers::pi), 2.0, 1e-12);
    EXPECT_NEAR(equal_area_diameter(ring_area(projected_hull(points))), 4.0 / std::sqrt(std::numbers::pi), 1e-9);
    EXPECT_TRUE(projected_hull(std::vector<Eigen::Vector3f>{{0, 0, 0}, {1, 1, 1}}).empty());
    EXPECT_TRUE(projected_hull(std::vector<Eigen::Vector3f>{{0, 0, 0}, {1, 1, 1}, {2, 2, 5}}).empty());  // on a line
    EXPECT_EQ(ring_area({}), 0.0);
    EXPECT_EQ(equal_area_diameter(0.0), 0.0);
}

// The outline GeoJSON takes: the hull's corners only (the inner point and the one on an edge
// left out), counter-clockwise, not closed.
TEST(ProjectedHull, CornersRunCounterClockwise) {
    const std::vector<Eigen::Vector3f> points{{0, 0, 1}, {2, 0, 3}, {1, 0, 2}, {2, 2, 0}, {0, 2, 5}, {1, 1, 9}};
    const std::vector<Eigen::Vector2d> ring = projected_hull(points);
    ASSERT_EQ(ring.size(), 4u);
    double twice_signed_area = 0.0;
    for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
        twice_signed_area += ring[j].x() * ring[i].y() - ring[i].x() * ring[j].y();
    EXPECT_NEAR(twice_signed_area, 8.0, 1e-9);  // positive: counter-clockwise
    for (const Eigen::Vector2d& corner : ring) EXPECT_TRUE((corner.x() == 0 || corner.x() == 2) && (corner.y() == 0 || corner.y() == 2));
}
