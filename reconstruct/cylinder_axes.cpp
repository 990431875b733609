#include "reconstruct/cylinder_axes.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "reconstruct/internode_points.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

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

// Branch axes: from the root along main children to a tip, and from every fork along each
// lateral child (the fork is the first node of its laterals' axes).
std::vector<std::vector<int>> branch_axes(const TreeGraph& tree) {
    std::vector<std::vector<int>> axes;
    for (int u : tree.preorder()) {
        const auto& kids = tree.nodes[u].children;
        for (std::size_t k = u == 0 ? 0 : 1; k < kids.size(); ++k) {  // a main child continues u's own axis
            std::vector<int> axis{u, kids[k]};
            while (!tree.nodes[axis.back()].children.empty()) axis.push_back(tree.nodes[axis.back()].children.front());
            axes.push_back(std::move(axis));
        }
    }
    return axes;
}

// Pooled RMS distance of the points of the internodes axis[lo..hi] from their own internode's
// centroid, across that internode's segment: the size of the branch's cross-section (about r for
// a ring, 0.55-0.8 r for the arc a one-sided scan sees), whatever the bends of the stretch.
double cross_section_spread(const TreeGraph& tree, const std::vector<int>& axis, std::size_t lo, std::size_t hi,
                            std::span<const Eigen::Vector3f> points, const std::vector<std::size_t>& start,
                            const std::vector<int>& grouped) {
    double sum = 0, dof = 0;
    for (std::size_t j = lo; j <= hi; ++j) {
        const auto v = static_cast<std::size_t>(axis[j]);
        const std::size_t count = start[v + 1] - start[v];
        const Eigen::Vector3d a = tree.nodes[axis[j - 1]].position.cast<double>();
        const Eigen::Vector3d seg = tree.nodes[v].position.cast<double>() - a;
        if (count < 2 || seg.norm() < 1e-9) continue;
        const Eigen::Vector3d t = seg.normalized();
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        double sq = 0;
        for (std::size_t k = start[v]; k < start[v + 1]; ++k) {
            const Eigen::Vector3d q = points[grouped[k]].cast<double>() - a;
            const Eigen::Vector3d l = q - t * q.dot(t);
            mean += l;
            sq += l.squaredNorm();
        }
        sum += sq - mean.squaredNorm() / static_cast<double>(count);
        dof += static_cast<double>(count - 1);
    }
    return dof > 0 ? std::sqrt(std::max(0.0, sum / dof)) : 0.0;
}

void check_options(const CylinderAxesOptions& o) {
    auto positive = [](double v) { return v > 0 && std::isfinite(v); };
    if (!positive(o.window)) throw Error::usage("cylinder axes: window must be > 0");
    if (o.min_points < 6) throw Error::usage("cylinder axes: minimum points must be >= 6");
    if (!positive(o.min_radius) || !positive(o.max_radius) || o.min_radius >= o.max_radius)
        throw Error::usage("cylinder axes: radius limits must satisfy 0 < minimum < maximum");
    if (!positive(o.max_rms)) throw Error::usage("cylinder axes: maximum RMS must be > 0");
    if (!(o.min_spread >= 0 && std::isfinite(o.min_spread))) throw Error::usage("cylinder axes: minimum spread must be >= 0");
    if (!(o.min_arc >= 0 && o.min_arc <= 360)) throw Error::usage("cylinder axes: minimum arc must be in 0..360 degrees");
    if (!(o.max_tilt >= 0 && o.max_tilt <= 90)) throw Error::usage("cylinder axes: maximum tilt must be in 0..90 degrees");
    if (!positive(o.max_shift)) throw Error::usage("cylinder axes: maximum shift must be > 0");
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

std::size_t fit_cylinder_axes(TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                              const CylinderAxesOptions& o, const std::vector<bool>& fixed) {
    check_options(o);
    if (points.size() != point_internode.size()) throw Error(ExitCode::Internal, "cylinder axes: one internode per point expected");
    if (!fixed.empty() && fixed.size() != tree.size()) throw Error(ExitCode::Internal, "cylinder axes: one fixed flag per node expected");
    if (!o.enabled || tree.size() < 2) return 0;

    const std::size_t n = tree.size();
    const InternodePoints groups = group_by_internode(point_internode, n);
    const std::vector<std::size_t>& start = groups.start;
    const std::vector<int>& grouped = groups.index;

    // A stretch of a dense scan holds thousands of points; an even subset pins the cylinder as
    // well and keeps the fits' cost bounded (OR_wood: windows of up to ~1,100 points).
    constexpr std::size_t kMaxFitPoints = 80;
    const double cos_tilt = std::cos(o.max_tilt * std::numbers::pi / 180.0);
    std::vector<Eigen::Vector3f> shift(n, Eigen::Vector3f::Zero());
    std::vector<int> members;
    std::vector<Eigen::Vector3d> window;
    std::size_t moved = 0, tried = 0;
    std::size_t rejected[6] = {};  // fits: no fit, radius, residual or spread, arc, tilt; nodes: shift
    for (const auto& axis : branch_axes(tree)) {
        std::vector<double> s(axis.size(), 0.0);
        for (std::size_t i = 1; i < axis.size(); ++i)
            s[i] = s[i - 1] + (tree.nodes[axis[i]].position - tree.nodes[axis[i - 1]].position).norm();
        // Cylinders are fitted to windows centred on nodes a quarter window apart; every node
        // takes the fit centred nearest to it (neighbouring windows share most of their points,
        // so a fit per node would cost several times as much for the same axes).
        std::vector<std::size_t> centres;
        for (std::size_t i = 1; i < axis.size(); ++i)
            if (centres.empty() || s[i] - s[centres.back()] >= 0.25 * o.window || i + 1 == axis.size()) centres.push_back(i);
        std::vector<std::optional<CylinderFit>> fits(centres.size());
        for (std::size_t c = 0; c < centres.size(); ++c) {
            const std::size_t i = centres[c];
            // Internodes j (segment axis[j-1] -> axis[j]) whose middle lies within half a window.
            std::size_t lo = i, hi = i;
            while (lo > 1 && s[i] - 0.5 * (s[lo - 2] + s[lo - 1]) <= 0.5 * o.window) --lo;
            while (hi + 1 < axis.size() && 0.5 * (s[hi] + s[hi + 1]) - s[i] <= 0.5 * o.window) ++hi;
            bool any_free = fixed.empty();
            for (std::size_t j = lo; j <= hi && !any_free; ++j) any_free = !fixed[static_cast<std::size_t>(axis[j])];
            if (!any_free) continue;
            members.clear();
            for (std::size_t j = lo; j <= hi; ++j) {
                const auto v = static_cast<std::size_t>(axis[j]);
                members.insert(members.end(), grouped.begin() + static_cast<long>(start[v]), grouped.begin() + static_cast<long>(start[v + 1]));
            }
            if (members.size() < static_cast<std::size_t>(o.min_points)) continue;
            const Eigen::Vector3d a = tree.nodes[axis[lo - 1]].position.cast<double>();
            const Eigen::Vector3d b = tree.nodes[axis[hi]].position.cast<double>();
            if ((b - a).norm() < 1e-9) continue;
            const Eigen::Vector3d d0 = (b - a).normalized();
            const Eigen::Vector3d node = tree.nodes[axis[i]].position.cast<double>();
            window.clear();
            const std::size_t stride = (members.size() + kMaxFitPoints - 1) / kMaxFitPoints;
            for (std::size_t k = 0; k < members.size(); k += stride) window.push_back(points[members[k]].cast<double>());
            // Start: the skeleton's own axis through the node, radius the points' mean distance from it.
            double r0 = 0;
            for (const auto& p : window) {
                const Eigen::Vector3d q = p - node;
                r0 += (q - d0 * q.dot(d0)).norm();
            }
            r0 /= static_cast<double>(window.size());
            ++tried;
            const CylinderFit fit = fit_cylinder(window, node, d0, r0);
            const double r = fit.radius;
            int reason = -1;
            if (!fit.converged) reason = 0;
            else if (!(r >= o.min_radius && r <= o.max_radius)) reason = 1;
            else if (fit.rms > o.max_rms * r || cross_section_spread(tree, axis, lo, hi, points, start, grouped) < o.min_spread * r)
                reason = 2;
            else if (fit.arc < o.min_arc) reason = 3;
            else if (std::abs(fit.direction.dot(d0)) < cos_tilt) reason = 4;
            if (reason >= 0) ++rejected[reason];
            else fits[c] = fit;
        }
        std::size_t c = 0;
        for (std::size_t i = 1; i < axis.size(); ++i) {
            while (c + 1 < centres.size() && std::abs(s[centres[c + 1]] - s[i]) < std::abs(s[centres[c]] - s[i])) ++c;
            const auto u = static_cast<std::size_t>(axis[i]);
            if (!fits[c] || (!fixed.empty() && fixed[u])) continue;
            const CylinderFit& fit = *fits[c];
            const Eigen::Vector3d node = tree.nodes[u].position.cast<double>();
            const Eigen::Vector3d target = fit.point + fit.direction * (node - fit.point).dot(fit.direction);
            if ((target - node).norm() > o.max_shift * fit.radius) {
                ++rejected[5];
                continue;
            }
            shift[u] = (target - node).cast<float>();
            ++moved;
        }
    }
    for (std::size_t u = 1; u < n; ++u) tree.nodes[u].position += shift[u];
    log_debug("cylinder axes: " + std::to_string(moved) + " nodes moved, " + std::to_string(tried) + " fits; rejected: no fit " +
              std::to_string(rejected[0]) + ", radius " + std::to_string(rejected[1]) + ", residual or spread " + std::to_string(rejected[2]) +
              ", arc " + std::to_string(rejected[3]) + ", tilt " + std::to_string(rejected[4]) + ", nodes beyond the shift limit " + std::to_string(rejected[5]));
    return moved;
}

}  // namespace treelobes
