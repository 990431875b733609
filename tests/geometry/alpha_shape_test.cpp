#include "geometry/alpha_shape.hpp"
#include "geometry/closed_mesh.hpp"

#include "core/error.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

using namespace treelobes;
using treelobes::test::error_code_of;

namespace {

// Points filling a ball of radius r (a dense foliage cluster), fixed seed.
std::vector<Eigen::Vector3f> ball(float r, int n, unsigned seed = 3) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-r, r);
    std::vector<Eigen::Vector3f> points;
    while (static_cast<int>(points.size()) < n) {
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const float z = u(rng), y = u(rng), x = u(rng);
        const Eigen::Vector3f p(x, y, z);
        if (p.norm() <= r) points.push_back(p + Eigen::Vector3f(2, 3, 4));
    }
    return points;
}

}  // namespace

TEST(AlphaShape, BallBecomesOneClosedOutwardSurfaceOfAboutItsVolume) {
    const auto points = ball(0.5f, 3000);
    const AlphaShapeResult r = alpha_shape(points);
    ASSERT_TRUE(r.failure.empty()) << r.failure;
    EXPECT_TRUE(check_closed(r.mesh).closed());
    int components = 0;
    face_components(r.mesh, &components);
    EXPECT_EQ(components, 1);
    const double ball_volume = 4.0 / 3.0 * std::numbers::pi * 0.125;
    EXPECT_GT(r.mesh.signed_volume(), 0.8 * ball_volume);  // outward and nearly the whole ball
    EXPECT_LT(r.mesh.signed_volume(), 1.0 * ball_volume);  // a hull of points inside the ball
    EXPECT_NEAR(r.alpha_radius, 5.0 * r.alpha_min_radius, 1e-9);
    EXPECT_GT(r.alpha_min_radius, 0.0);
}

TEST(AlphaShape, LargerFactorGivesALargerHull) {
    // Two blobs joined by a thin bridge: a small alpha follows the waist, a large one fills it.
    auto points = ball(0.3f, 1500, 1);
    for (auto p : ball(0.3f, 1500, 2)) points.push_back(p + Eigen::Vector3f(1.0f, 0, 0));
    for (int i = 0; i <= 40; ++i) points.push_back(Eigen::Vector3f(2.3f + 0.4f * i / 40.0f, 3, 4));
    const AlphaShapeResult tight = alpha_shape(points, {1.5});
    const AlphaShapeResult loose = alpha_shape(points, {20.0});
    ASSERT_TRUE(tight.failure.empty()) << tight.failure;
    ASSERT_TRUE(loose.failure.empty()) << loose.failure;
    EXPECT_TRUE(check_closed(tight.mesh).closed());
    EXPECT_TRUE(check_closed(loose.mesh).closed());
    EXPECT_GT(loose.mesh.signed_volume(), tight.mesh.signed_volume());
}

TEST(AlphaShape, FlatOrTinyClustersHaveNoShape) {
    std::vector<Eigen::Vector3f> flat;
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) flat.emplace_back(0.1f * i, 0.1f * j, 1.0f);
    EXPECT_FALSE(alpha_shape(flat).failure.empty());
    EXPECT_FALSE(alpha_shape(std::vector<Eigen::Vector3f>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}).failure.empty());
    EXPECT_EQ(error_code_of([&] { alpha_shape(flat, {0.5}); }), ExitCode::Usage);
}

TEST(SimplifyClosedMesh, StaysClosedAndWithinTheFaceLimit) {
    TriangleMesh mesh = alpha_shape(ball(0.5f, 3000)).mesh;
    const double volume = mesh.signed_volume();
    ASSERT_GT(mesh.faces.size(), 200u);
    SimplifyOptions o;
    o.max_faces = 100;
    o.tolerance = 0.0;
    ASSERT_TRUE(simplify_closed_mesh(mesh, o));
    EXPECT_LE(mesh.faces.size(), 100u);
    EXPECT_TRUE(check_closed(mesh).closed());
    EXPECT_NEAR(mesh.signed_volume(), volume, 0.15 * volume);
}

// How far `mesh` falls short of `target`'s bounding box, the largest shortfall over the six sides.
float extent_shortfall(const TriangleMesh& mesh, const TriangleMesh& target) {
    Eigen::Vector3f lo = mesh.vertices[0], hi = lo, tlo = target.vertices[0], thi = tlo;
    for (const auto& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
    for (const auto& v : target.vertices) tlo = tlo.cwiseMin(v), thi = thi.cwiseMax(v);
    return std::max((lo - tlo).maxCoeff(), (thi - hi).maxCoeff());
}

TEST(InflateToContain, ASimplifiedSurfaceGetsBackTheExtentItLost) {
    const TriangleMesh fine = alpha_shape(ball(0.5f, 3000)).mesh;
    TriangleMesh coarse = fine;
    SimplifyOptions o;
    o.max_faces = 24;
    o.tolerance = 0.0;
    ASSERT_TRUE(simplify_closed_mesh(coarse, o));
    // Edge collapse cut the ball's caps: the coarse surface is smaller and narrower.
    EXPECT_LT(coarse.signed_volume(), 0.9 * fine.signed_volume());
    EXPECT_GT(extent_shortfall(coarse, fine), 0.02f);
    const auto faces = coarse.faces;
    inflate_to_contain(coarse, fine);
    EXPECT_EQ(coarse.faces, faces);
    EXPECT_TRUE(check_closed(coarse).closed());
    EXPECT_GT(coarse.signed_volume(), fine.signed_volume());
    EXPECT_LT(extent_shortfall(coarse, fine), 0.01f);
    // A surface that already holds the fine one stays as it is.
    TriangleMesh wider = fine;
    const Eigen::Vector3f centre(2, 3, 4);
    for (auto& v : wider.vertices) v = centre + 1.3f * (v - centre);
    const auto before = wider.vertices;
    inflate_to_contain(wider, fine);
    EXPECT_EQ(wider.vertices, before);
}

TEST(ClosedMesh, TwoTetrahedraSharingAnEdgeAreSplitIntoAManifold) {
    // Tetrahedra (0,1,2,3) and (0,1,4,5) share edge 0-1: four faces around it.
    TriangleMesh m;
    m.vertices = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0.5f}, {0.5f, 1, 0.5f}, {-1, 0, 0.5f}, {-0.5f, -1, 0.5f}};
    auto tetra = [&](int a, int b, int c, int d) {
        // Orient each face outward: its normal points away from the fourth vertex.
        auto add = [&](int x, int y, int z, int w) {
            const Eigen::Vector3f n = (m.vertices[y] - m.vertices[x]).cross(m.vertices[z] - m.vertices[x]);
            if (n.dot(m.vertices[w] - m.vertices[x]) > 0)
                m.faces.push_back({x, z, y});
            else
                m.faces.push_back({x, y, z});
        };
        add(a, b, c, d);
        add(a, b, d, c);
        add(a, c, d, b);
        add(b, c, d, a);
    };
    tetra(0, 1, 2, 3);
    tetra(0, 1, 4, 5);
    EXPECT_FALSE(check_closed(m).closed());  // edge 0-1 is used twice in each direction
    ASSERT_TRUE(make_closed_manifold(m));
    EXPECT_TRUE(check_closed(m).closed());
    int components = 0;
    face_components(m, &components);
    EXPECT_EQ(components, 2);
    EXPECT_GT(m.signed_volume(), 0);
}
