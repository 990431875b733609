#include "geometry/cylinder_fit.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace treelobes {

namespace {

// Two unit vectors completing `d` (unit) to an orthonormal frame.
std::pair<Eigen::Vector3d, Eigen::Vector3d> frame_of(const Eigen::Vector3d& d) {
    const Eigen::Vector3d helper = std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d e1 = d.cross(helper).normalized();
    return {e1, d.cross(e1)};
}

struct Cylinder {
    Eigen::Vector3d c, d;
    double r;
};

double cost_of(std::span<const Eigen::Vector3d> points, const Cylinder& m) {
    double sum = 0;
    for (const auto& p : points) {
        const Eigen::Vector3d q = p - m.c;
        const double f = (q - m.d * q.dot(m.d)).norm() - m.r;
        sum += f * f;
    }
    return sum;
}

// Levenberg-Marquardt over (two offsets of the axis point across the axis, two tilts of the
// direction, the radius), re-parametrised around the current cylinder at every step so that the
// axis never degenerates. Residual f = |(p - c) x d| - r, Jacobian analytic: with n the unit
// vector from the axis to p and h = (p - c).d, df/dc = -n, df/dtilt_k = -(n.e_k) h, df/dr = -1.
bool levenberg_marquardt(std::span<const Eigen::Vector3d> points, Cylinder& m) {
    constexpr int kMaxIterations = 40;
    double lambda = 1e-3;
    double cost = cost_of(points, m);
    for (int it = 0; it < kMaxIterations; ++it) {
        const auto [e1, e2] = frame_of(m.d);
        Eigen::Matrix<double, 5, 5> a = Eigen::Matrix<double, 5, 5>::Zero();
        Eigen::Matrix<double, 5, 1> g = Eigen::Matrix<double, 5, 1>::Zero();
        for (const auto& p : points) {
            const Eigen::Vector3d q = p - m.c;
            const double h = q.dot(m.d);
            const Eigen::Vector3d w = q - m.d * h;
            const double dist = w.norm();
            const Eigen::Vector3d n = dist > 1e-12 ? Eigen::Vector3d(w / dist) : e1;
            const double ne1 = n.dot(e1), ne2 = n.dot(e2);
            Eigen::Matrix<double, 5, 1> j;
            j << -ne1, -ne2, -ne1 * h, -ne2 * h, -1.0;
            a.noalias() += j * j.transpose();
            g += j * (dist - m.r);
        }
        bool improved = false;
        while (lambda < 1e12) {
            Eigen::Matrix<double, 5, 5> damped = a;
            for (int k = 0; k < 5; ++k) damped(k, k) += lambda * std::max(a(k, k), 1e-12);
            const Eigen::Matrix<double, 5, 1> step = damped.ldlt().solve(-g);
            if (!step.allFinite()) return false;
            Cylinder next{m.c + step(0) * e1 + step(1) * e2, (m.d + step(2) * e1 + step(3) * e2).normalized(), m.r + step(4)};
            const double next_cost = cost_of(points, next);
            if (next_cost < cost) {
                // Converged: a step below a micrometre / microradian, or a cost that barely changes.
                const bool small = (std::abs(step(0)) + std::abs(step(1)) + std::abs(step(4)) < 1e-6 &&
                                    std::abs(step(2)) + std::abs(step(3)) < 1e-6) ||
                                   cost - next_cost < 1e-8 * cost;
                m = next;
                cost = next_cost;
                lambda = std::max(lambda * 0.1, 1e-9);
                improved = true;
                if (small) return true;
                break;
            }
            lambda *= 10;
        }
        if (!improved) return true;  // no step lowers the cost: a minimum (to rounding)
    }
    return true;
}

// RMS residual and the angle around the axis covered by points.
void describe(std::span<const Eigen::Vector3d> points, CylinderFit& fit) {
    const auto [e1, e2] = frame_of(fit.direction);
    std::vector<double> angle;
    angle.reserve(points.size());
    double sum = 0;
    for (const auto& p : points) {
        const Eigen::Vector3d q = p - fit.point;
        const Eigen::Vector3d w = q - fit.direction * q.dot(fit.direction);
        const double f = w.norm() - fit.radius;
        sum += f * f;
        angle.push_back(std::atan2(w.dot(e2), w.dot(e1)));
    }
    fit.rms = std::sqrt(sum / static_cast<double>(points.size()));
    std::sort(angle.begin(), angle.end());
    double widest = angle.front() + 2 * std::numbers::pi - angle.back();
    for (std::size_t i = 1; i < angle.size(); ++i) widest = std::max(widest, angle[i] - angle[i - 1]);
    fit.arc = 360.0 - widest * 180.0 / std::numbers::pi;
}

CylinderFit fit_once(std::span<const Eigen::Vector3d> points, Cylinder m) {
    CylinderFit fit;
    if (!levenberg_marquardt(points, m) || !m.c.allFinite() || !m.d.allFinite() || !std::isfinite(m.r)) return fit;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : points) mean += p;
    mean /= static_cast<double>(points.size());
    fit.converged = true;
    fit.direction = m.d;
    fit.point = m.c + m.d * (mean - m.c).dot(m.d);
    fit.radius = m.r;
    describe(points, fit);
    return fit;
}

}  // namespace

CylinderFit fit_cylinder(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& point, const Eigen::Vector3d& direction,
                         double radius) {
    if (points.size() < 6 || direction.norm() < 1e-12) return {};
    CylinderFit fit = fit_once(points, {point, direction.normalized(), radius});
    if (!fit.converged) return fit;
    // One trimming round: bark of a neighbouring twig or a stray point in the stretch.
    std::vector<Eigen::Vector3d> kept;
    kept.reserve(points.size());
    for (const auto& p : points) {
        const Eigen::Vector3d q = p - fit.point;
        if (std::abs((q - fit.direction * q.dot(fit.direction)).norm() - fit.radius) <= 3.0 * fit.rms) kept.push_back(p);
    }
    if (kept.size() == points.size() || kept.size() < 6) return fit;
    return fit_once(kept, {fit.point, fit.direction, fit.radius});
}

}  // namespace treelobes
