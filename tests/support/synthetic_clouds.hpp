// Synthetic point clouds with a known skeleton for the reconstruct tests: points on the bark
// of cylinders along segments, with a fixed random seed so every run sees the same cloud.
#pragma once

#include "core/point_cloud.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace treelobes::test {

struct Segment {
    Eigen::Vector3f a, b;
    float radius;
};

// `density` points per square metre of bark; `visible` is the fraction of the circumference
// scanned (1 = all round; 0.5 = one side, facing +x); `noise` is Gaussian, metres.
inline void add_cylinder(std::vector<Eigen::Vector3f>& points, const Segment& s, float density, std::mt19937& rng, float visible = 1.0f,
                         float noise = 0.002f) {
    const Eigen::Vector3f axis = s.b - s.a;
    const float length = axis.norm();
    const Eigen::Vector3f t = axis / length;
    // Fixed frame: u points towards +x as far as possible, so "visible" means the +x side.
    Eigen::Vector3f u = Eigen::Vector3f::UnitX() - Eigen::Vector3f::UnitX().dot(t) * t;
    if (u.norm() < 1e-3f) u = t.unitOrthogonal();
    u.normalize();
    const Eigen::Vector3f v = t.cross(u);
    const auto count = static_cast<int>(density * 2.0f * std::numbers::pi_v<float> * s.radius * length * visible);
    std::uniform_real_distribution<float> along(0.0f, length);
    std::uniform_real_distribution<float> angle(-std::numbers::pi_v<float> * visible, std::numbers::pi_v<float> * visible);
    std::normal_distribution<float> jitter(0.0f, noise);
    for (int i = 0; i < count; ++i) {
        const float a = angle(rng);
        const Eigen::Vector3f n = std::cos(a) * u + std::sin(a) * v;
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const float jitter_z = jitter(rng), jitter_y = jitter(rng), jitter_x = jitter(rng);
        const Eigen::Vector3f jitter3(jitter_x, jitter_y, jitter_z);
        points.push_back(s.a + along(rng) * t + s.radius * n + jitter3);
    }
}

inline PointCloud cloud_from(const std::vector<Segment>& segments, float density, unsigned seed = 7, float visible = 1.0f) {
    std::mt19937 rng(seed);
    PointCloud cloud;
    for (const auto& s : segments) add_cylinder(cloud.positions, s, density, rng, visible);
    return cloud;
}

// A trunk 0..2 m (r 10 cm) forking into two 1.4 m branches (r 5 cm) leaning +x and -x.
inline std::vector<Segment> y_tree() {
    return {{{0, 0, 0}, {0, 0, 2}, 0.10f}, {{0, 0, 2}, {1.0f, 0, 3.0f}, 0.05f}, {{0, 0, 2}, {-0.8f, 0, 2.9f}, 0.05f}};
}

// Distance from p to the nearest of the segments' axes.
inline float distance_to_axes(const Eigen::Vector3f& p, const std::vector<Segment>& segments) {
    float best = 1e9f;
    for (const auto& s : segments) {
        const Eigen::Vector3f ab = s.b - s.a;
        const float t = std::clamp((p - s.a).dot(ab) / ab.squaredNorm(), 0.0f, 1.0f);
        best = std::min(best, (s.a + t * ab - p).norm());
    }
    return best;
}

}  // namespace treelobes::test
