// Small point sets for the kd-tree, neighbour-graph and shortest-path tests.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <random>
#include <vector>

namespace treelobes::test {

// n points drawn uniformly from the cube [0, scale)^3.
inline std::vector<Eigen::Vector3f> random_points(int n, unsigned seed, float scale = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, scale);
    std::vector<Eigen::Vector3f> points(n);
    for (auto& p : points) p = {u(rng), u(rng), u(rng)};
    return points;
}

// Appends points every `step` metres from a to b (both included).
inline void add_line(std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& a, const Eigen::Vector3f& b, float step) {
    const int n = static_cast<int>(std::round((b - a).norm() / step));
    for (int i = 0; i <= n; ++i) points.push_back(a + (b - a) * (static_cast<float>(i) / static_cast<float>(n)));
}

}  // namespace treelobes::test
