#include "reconstruct/cylinder_axes.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "geometry/cylinder_fit.hpp"
#include "reconstruct/internode_points.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

namespace treelobes {

namespace {

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
                members.insert(members.end(), grouped.begin() + static_cast<long>(start[v]),
                               grouped.begin() + static_cast<long>(start[v + 1]));
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
            if (!fit.converged)
                reason = 0;
            else if (!(r >= o.min_radius && r <= o.max_radius))
                reason = 1;
            else if (fit.rms > o.max_rms * r || cross_section_spread(tree, axis, lo, hi, points, start, grouped) < o.min_spread * r)
                reason = 2;
            else if (fit.arc < o.min_arc)
                reason = 3;
            else if (std::abs(fit.direction.dot(d0)) < cos_tilt)
                reason = 4;
            if (reason >= 0)
                ++rejected[reason];
            else
                fits[c] = fit;
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
              std::to_string(rejected[0]) + ", radius " + std::to_string(rejected[1]) + ", residual or spread " +
              std::to_string(rejected[2]) + ", arc " + std::to_string(rejected[3]) + ", tilt " + std::to_string(rejected[4]) +
              ", nodes beyond the shift limit " + std::to_string(rejected[5]));
    return moved;
}

}  // namespace treelobes
