// Error metrics: Hausdorff distances between skeletons and the √3·d/2 vertex bound.
#include "encode/hausdorff.hpp"
#include "random_tree.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

TreeGraph stick() {
    TreeGraph tree;
    tree.add_node({0, 0, 0}, 0.1f, -1);
    tree.add_node({0, 0, 1}, 0.1f, 0);
    return tree;
}

// Brute force directed distances with the documented sampling (root + points ≤ step apart).
std::pair<double, double> brute_force(const TreeGraph& from, const TreeGraph& to, double step) {
    auto world = [](const TreeGraph& t, int i) { return Eigen::Vector3d(t.nodes[i].position.cast<double>() + t.origin); };
    auto nearest = [&](const Eigen::Vector3d& p) {
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t i = 1; i < to.size(); ++i) {
            const Eigen::Vector3d a = world(to, to.nodes[i].parent), b = world(to, static_cast<int>(i));
            const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
            best = std::min(best, (p - (a + t * (b - a))).norm());
        }
        return best;
    };
    double max = nearest(world(from, 0)), sum = max;
    std::size_t count = 1;
    for (std::size_t i = 1; i < from.size(); ++i) {
        const Eigen::Vector3d a = world(from, from.nodes[i].parent), b = world(from, static_cast<int>(i));
        const auto pieces = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil((b - a).norm() / step)));
        for (std::size_t k = 1; k <= pieces; ++k) {
            const double d = nearest(a + (b - a) * (static_cast<double>(k) / pieces));
            max = std::max(max, d);
            sum += d;
            ++count;
        }
    }
    return {max, sum / count};
}

}  // namespace

TEST(Hausdorff, IdenticalSkeletonsHaveZeroDistance) {
    const TreeGraph tree = test::random_tree({}, 5);
    const auto h = skeleton_hausdorff(tree, tree);
    EXPECT_NEAR(h.max, 0.0, 1e-6);
    EXPECT_NEAR(h.mean, 0.0, 1e-7);
    EXPECT_GT(h.diagonal, 0.0);
    EXPECT_GT(h.samples, 2 * tree.size());
}

TEST(Hausdorff, ExtraBranchCountsInOneDirection) {
    const TreeGraph a = stick();
    TreeGraph b = stick();
    b.add_node({1, 0, 1}, 0.05f, 1);
    const auto h = skeleton_hausdorff(a, b);
    EXPECT_NEAR(h.forward_max, 0.0, 1e-9);
    EXPECT_NEAR(h.backward_max, 1.0, 1e-9);
    EXPECT_NEAR(h.max, 1.0, 1e-9);
    EXPECT_NEAR(h.diagonal, 1.0, 1e-9);
    EXPECT_NEAR(h.max_normalised, 1.0, 1e-9);
    // Backward samples: root, 1000 on the stick at distance 0, 1000 on the branch at k/1000.
    EXPECT_NEAR(h.backward_mean, 500.5 / 2001.0, 1e-9);
    EXPECT_NEAR(h.mean, 0.5 * 500.5 / 2001.0, 1e-9);
}

TEST(Hausdorff, ComparesInOriginalCoordinates) {
    const TreeGraph a = stick();
    TreeGraph b = stick();
    b.origin = {0.25, 0, 0};  // same local positions, shifted tree
    EXPECT_NEAR(skeleton_hausdorff(a, b).max, 0.25, 1e-9);
    for (auto& node : b.nodes) node.position.x() -= 0.25f;
    EXPECT_NEAR(skeleton_hausdorff(a, b).max, 0.0, 1e-7);
}

TEST(Hausdorff, GridSearchMatchesBruteForce) {
    test::RandomTreeProfile profile;
    profile.max_nodes = 150;
    profile.max_laterals = 3;
    profile.wiggle_degrees = 20;
    for (std::uint32_t seed = 1; seed <= 10; ++seed) {
        const TreeGraph a = test::random_tree(profile, seed);
        TreeGraph b = test::random_tree(profile, seed + 100);
        b.origin = {0.3, -0.2, 0.5};
        const double step = 0.02;
        const auto h = skeleton_hausdorff(a, b, {step});
        const auto [forward_max, forward_mean] = brute_force(a, b, step);
        const auto [backward_max, backward_mean] = brute_force(b, a, step);
        EXPECT_NEAR(h.forward_max, forward_max, 1e-9);
        EXPECT_NEAR(h.forward_mean, forward_mean, 1e-9);
        EXPECT_NEAR(h.backward_max, backward_max, 1e-9);
        EXPECT_NEAR(h.backward_mean, backward_mean, 1e-9);
    }
}

TEST(Hausdorff, VertexBoundDetectsAVertexOutsideItsVoxel) {
    const TreeGraph original = stick();
    TreeGraph decoded = stick();
    const double d = 0.1;
    decoded.nodes[1].position.x() += 0.08f;  // within √3·0.1/2 ≈ 0.0866
    auto check = check_vertex_error(original, decoded, {0, 1}, d);
    EXPECT_TRUE(check.within_bound);
    EXPECT_NEAR(check.bound, std::sqrt(3.0) * d / 2.0, 1e-12);
    EXPECT_NEAR(check.max_error, 0.08, 1e-6);
    decoded.nodes[1].position.x() += 0.01f;
    check = check_vertex_error(original, decoded, {0, 1}, d);
    EXPECT_FALSE(check.within_bound);
}
