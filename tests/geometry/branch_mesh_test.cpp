#include "core/error.hpp"
#include "core/mesh_io.hpp"
#include "geometry/branch_mesh.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <numbers>

using namespace treelobes;

namespace {

// Trunk 0-1-2 along z and a lateral 1-3 leaving at 1 m.
TreeGraph fork_tree() {
    TreeGraph tree;
    tree.add_node({0, 0, 0}, 0.20f, -1);
    tree.add_node({0, 0, 1}, 0.15f, 0);
    tree.add_node({0, 0, 2}, 0.10f, 1);
    tree.add_node({0.8f, 0, 1.6f}, 0.05f, 1);
    return tree;
}

// A helix: the frames must follow it without twisting.
TreeGraph helix_tree(int nodes) {
    TreeGraph tree;
    for (int i = 0; i < nodes; ++i) {
        const float a = 0.35f * static_cast<float>(i);
        tree.add_node({std::cos(a), std::sin(a), 0.15f * static_cast<float>(i)}, 0.05f, i - 1);
    }
    return tree;
}

// Edges of the mesh and how many faces use each (undirected).
std::map<std::pair<int, int>, int> edge_use(const TriangleMesh& mesh) {
    std::map<std::pair<int, int>, int> use;
    for (const auto& f : mesh.faces)
        for (int k = 0; k < 3; ++k) {
            const int a = f[k], b = f[(k + 1) % 3];
            ++use[{std::min(a, b), std::max(a, b)}];
        }
    return use;
}

}  // namespace

TEST(BranchMesh, StraightTubeIsAClosedPrismWithTheRightVolume) {
    TreeGraph tree;
    tree.add_node({0, 0, 0}, 0.1f, -1);
    tree.add_node({0, 0, 1}, 0.1f, 0);
    tree.add_node({0, 0, 2}, 0.1f, 1);
    BranchMeshOptions options;
    options.sides = 12;
    const TriangleMesh mesh = build_branch_mesh(tree, options);
    // A regular 12-gon of circumradius r has area 0.5 * n * r^2 * sin(2 pi / n).
    const double polygon = 0.5 * 12 * 0.01 * std::sin(2 * std::numbers::pi / 12);
    EXPECT_NEAR(mesh.signed_volume(), polygon * 2.0, 1e-4);
    for (const auto& [edge, count] : edge_use(mesh)) EXPECT_EQ(count, 2) << edge.first << "-" << edge.second;
    // 2 internodes x 2 subdivisions + 1 = 5 rings, plus the two cap centres.
    EXPECT_EQ(mesh.vertex_count(), 5u * 12u + 2u);
}

TEST(BranchMesh, ForkGivesOneTubePerAxisWithLateralBaseInsideTheParent) {
    const TreeGraph tree = fork_tree();
    BranchMeshOptions options;  // 8 sides, 2 subdivisions
    const TriangleMesh mesh = build_branch_mesh(tree, options);
    // Trunk: 3 nodes -> 5 rings; lateral (fork + 1 node) -> 3 rings; 2 caps per tube.
    ASSERT_EQ(mesh.vertex_count(), (5u + 3u) * 8u + 4u);
    EXPECT_GT(mesh.signed_volume(), 0.0);
    // Each tube is closed: every edge is shared by exactly two faces.
    for (const auto& [edge, count] : edge_use(mesh)) EXPECT_EQ(count, 2);
    // The lateral's base ring (first ring of the second tube) lies inside the trunk tube.
    const int lateral_first = 5 * 8 + 2;
    for (int j = 0; j < 8; ++j) {
        const Eigen::Vector3f v = mesh.vertices[lateral_first + j];
        EXPECT_LE(std::hypot(v.x(), v.y()), 0.15f + 1e-5f) << "vertex " << j;
        EXPECT_NEAR((v - Eigen::Vector3f(0, 0, 1)).norm(), 0.05f, 1e-5f);
    }
}

TEST(BranchMesh, ParallelTransportFramesDoNotTwist) {
    const TreeGraph tree = helix_tree(30);
    BranchMeshOptions options;
    options.sides = 6;
    options.subdivisions = 3;
    const TriangleMesh mesh = build_branch_mesh(tree, options);
    const int rings = 29 * 3 + 1;
    ASSERT_EQ(mesh.vertex_count(), static_cast<std::size_t>(rings * 6 + 2));
    auto centre = [&](int ring) {
        Eigen::Vector3f c = Eigen::Vector3f::Zero();
        for (int j = 0; j < 6; ++j) c += mesh.vertices[ring * 6 + j];
        return Eigen::Vector3f(c / 6.0f);
    };
    for (int i = 0; i + 1 < rings; ++i) {
        const Eigen::Vector3f c0 = centre(i), c1 = centre(i + 1);
        const Eigen::Vector3f n0 = (mesh.vertices[i * 6] - c0).normalized();
        const Eigen::Vector3f n1 = (mesh.vertices[(i + 1) * 6] - c1).normalized();
        const Eigen::Vector3f t0 = n0.cross(mesh.vertices[i * 6 + 1] - c0).normalized();
        const Eigen::Vector3f t1 = n1.cross(mesh.vertices[(i + 1) * 6 + 1] - c1).normalized();
        // Carry n0 to ring i+1 by the minimal rotation t0 -> t1; what is left is twist.
        const Eigen::Vector3f carried = Eigen::Quaternionf::FromTwoVectors(t0, t1) * n0;
        const float twist = std::acos(std::clamp(carried.dot(n1), -1.0f, 1.0f));
        EXPECT_LT(twist, 0.02f) << "ring " << i;
        // Corresponding vertices stay close: no ring is rotated against its neighbour.
        for (int j = 0; j < 6; ++j) EXPECT_LT((mesh.vertices[i * 6 + j] - mesh.vertices[(i + 1) * 6 + j]).norm(), (c1 - c0).norm() + 0.02f);
    }
}

TEST(BranchMesh, LateralFrameFollowsTheParentFrame) {
    // The same fork built twice with the lateral mirrored: the lateral's first ring normal is
    // the parent's normal rotated minimally, so it does not depend on an arbitrary choice.
    const TreeGraph tree = fork_tree();
    const TriangleMesh mesh = build_branch_mesh(tree, {});
    const int trunk_ring_at_fork = 2;  // node 1 is the third ring of the trunk (2 subdivisions)
    const int lateral_first = 5 * 8 + 2;
    const Eigen::Vector3f trunk_n = (mesh.vertices[trunk_ring_at_fork * 8] - Eigen::Vector3f(0, 0, 1)).normalized();
    const Eigen::Vector3f lateral_n = (mesh.vertices[lateral_first] - Eigen::Vector3f(0, 0, 1)).normalized();
    const Eigen::Vector3f lateral_t = Eigen::Vector3f(0.8f, 0, 0.6f).normalized();
    const Eigen::Vector3f expected = Eigen::Quaternionf::FromTwoVectors(Eigen::Vector3f::UnitZ(), lateral_t) * trunk_n;
    EXPECT_GT(expected.dot(lateral_n), 0.999f);
}

TEST(BranchMesh, DeterministicAndWritable) {
    const TreeGraph tree = helix_tree(12);
    const TriangleMesh a = build_branch_mesh(tree, {});
    const TriangleMesh b = build_branch_mesh(tree, {});
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    for (std::size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]);
    EXPECT_EQ(a.faces, b.faces);
    test::TempDir dir;
    write_mesh(a, dir / "tube.ply");
    const TriangleMesh back = read_mesh(dir / "tube.ply");
    EXPECT_EQ(back.face_count(), a.face_count());
}

TEST(BranchMesh, ThinAxesCanBeLeftOut) {
    BranchMeshOptions options;
    options.min_axis_radius = 0.08f;  // keeps the trunk (0.2 m base), drops the 0.05 m lateral
    const TriangleMesh mesh = build_branch_mesh(fork_tree(), options);
    EXPECT_EQ(mesh.vertex_count(), 5u * 8u + 2u);
}

TEST(BranchMesh, DegenerateInputs) {
    TreeGraph single;
    single.add_node({0, 0, 0}, 0.1f, -1);
    EXPECT_EQ(build_branch_mesh(single, {}).vertex_count(), 0u);
    // Coincident nodes (zero-length internodes) are merged, not turned into NaN rings.
    TreeGraph repeated;
    repeated.add_node({0, 0, 0}, 0.1f, -1);
    repeated.add_node({0, 0, 0}, 0.1f, 0);
    repeated.add_node({0, 0, 1}, 0.1f, 1);
    repeated.add_node({0, 0, 1}, 0.05f, 2);
    repeated.add_node({0.5f, 0, 1}, 0.05f, 1);  // lateral from a merged node
    const TriangleMesh mesh = build_branch_mesh(repeated, {});
    ASSERT_GT(mesh.vertex_count(), 0u);
    for (const auto& v : mesh.vertices) EXPECT_TRUE(v.allFinite());
    BranchMeshOptions bad;
    bad.sides = 2;
    EXPECT_THROW(build_branch_mesh(fork_tree(), bad), Error);
    TreeGraph broken = fork_tree();
    broken.nodes[2].position.x() = std::nanf("");
    EXPECT_THROW(build_branch_mesh(broken, {}), Error);
}
