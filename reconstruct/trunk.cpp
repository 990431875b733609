#include "reconstruct/trunk.hpp"

#include "core/error.hpp"
#include "geometry/ransac_fit.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace treelobes {

namespace {

// Nodes of the main axis from the root (following the main child).
std::vector<int> main_axis(const TreeGraph& tree) {
    std::vector<int> axis{0};
    while (!tree.nodes[axis.back()].children.empty()) axis.push_back(tree.nodes[axis.back()].children.front());
    return axis;
}

// The main-axis point and direction where the axis first reaches height z.
bool axis_at_height(const TreeGraph& tree, const std::vector<int>& axis, float z, Eigen::Vector3f& point, Eigen::Vector3f& direction) {
    for (std::size_t i = 1; i < axis.size(); ++i) {
        const Eigen::Vector3f a = tree.nodes[axis[i - 1]].position, b = tree.nodes[axis[i]].position;
        if (z < std::min(a.z(), b.z()) || z > std::max(a.z(), b.z())) continue;
        const float t = std::abs(b.z() - a.z()) > 1e-6f ? (z - a.z()) / (b.z() - a.z()) : 0.0f;
        point = a + t * (b - a);
        // Direction over a few internodes: smoother than a single one.
        const Eigen::Vector3f low = tree.nodes[axis[i > 2 ? i - 3 : 0]].position;
        const Eigen::Vector3f high = tree.nodes[axis[std::min(axis.size() - 1, i + 2)]].position;
        direction = (high - low).norm() > 1e-6f ? Eigen::Vector3f((high - low).normalized()) : Eigen::Vector3f::UnitZ();
        return true;
    }
    return false;
}

StemSlice fit_slice(std::span<const Eigen::Vector3f> points, const std::vector<int>& candidates, const TreeGraph& tree,
                    const std::vector<int>& axis, float foot_z, float height, const TrunkOptions& o) {
    StemSlice slice;
    slice.height = height;
    Eigen::Vector3f centre, direction;
    if (!axis_at_height(tree, axis, foot_z + height, centre, direction)) return slice;
    // Plane across the stem: basis (u, v) orthogonal to the stem direction.
    const Eigen::Vector3f u = direction.unitOrthogonal(), v = direction.cross(u);
    std::vector<Eigen::Vector2f> projected;
    for (int i : candidates) {
        const Eigen::Vector3f d = points[i] - centre;
        const float along = d.dot(direction);
        if (std::abs(along) > 0.5f * o.slice_thickness) continue;
        const Eigen::Vector2f q(d.dot(u), d.dot(v));
        if (q.norm() <= o.max_radius) projected.push_back(q);
    }
    slice.points = projected.size();
    const CircleFit circle = fit_circle(projected, o.circle_tolerance, 0.01f, o.max_radius);
    if (!circle.ok) return slice;
    slice.centre = centre + circle.centre.x() * u + circle.centre.y() * v;
    slice.radius = circle.radius;
    slice.rms = circle.rms;
    slice.coverage = circle.coverage;
    slice.good = circle.coverage >= o.min_coverage && circle.inliers * 2 >= projected.size() && circle.rms < 0.25f * circle.radius;
    return slice;
}

float median(std::vector<float> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5f * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// The stem axis continued down to the foot: through the two lowest good slice centres (or
// straight down from the only one). The bottom of a scan is often too cluttered or too
// one-sided for a circle, the slices above it are not.
void locate_foot(TrunkFit& fit, float foot_z) {
    const StemSlice* first = nullptr;
    const StemSlice* second = nullptr;
    for (const auto& slice : fit.slices) {
        if (!slice.good) continue;
        if (!first)
            first = &slice;
        else if (!second && slice.height >= first->height + 0.3f)
            second = &slice;
    }
    if (!first) return;
    Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();
    if (second && second->centre.z() - first->centre.z() > 0.1f) direction = (second->centre - first->centre).normalized();
    if (direction.z() < 0.5f) direction = Eigen::Vector3f::UnitZ();  // implausible lean: keep vertical
    fit.foot_centre = first->centre - direction * ((first->centre.z() - foot_z) / direction.z());
    fit.foot_fitted = true;
}

}  // namespace

TrunkFit fit_trunk(std::span<const Eigen::Vector3f> points, const std::vector<int>& point_internode, const TreeGraph& tree,
                   const TrunkOptions& o) {
    if (point_internode.size() != points.size()) throw Error(ExitCode::Internal, "fit_trunk: one internode per point expected");
    TrunkFit fit;
    if (tree.size() < 2) return fit;
    const std::vector<int> axis = main_axis(tree);
    std::vector<bool> on_axis(tree.size(), false);
    for (int node : axis) on_axis[node] = true;
    const float foot_z = tree.nodes[0].position.z();
    const float top = o.breast_height + 0.2f;
    std::vector<int> candidates;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (point_internode[i] >= 0 && on_axis[point_internode[i]] && points[i].z() < foot_z + top + o.slice_thickness)
            candidates.push_back(static_cast<int>(i));

    std::vector<float> base;
    for (int k = 0;; ++k) {
        const float h = o.base_low + 0.1f * static_cast<float>(k);
        if (h > top + 1e-4f) break;
        StemSlice slice = fit_slice(points, candidates, tree, axis, foot_z, h, o);
        if (slice.good && h <= o.base_high + 1e-4f) base.push_back(2.0f * slice.radius);
        fit.slices.push_back(slice);
    }
    const StemSlice dbh = fit_slice(points, candidates, tree, axis, foot_z, o.breast_height, o);
    if (dbh.good) {
        fit.dbh_fitted = true;
        fit.dbh = 2.0f * dbh.radius;
    }
    locate_foot(fit, foot_z);
    if (!base.empty()) {
        fit.base_fitted = true;
        fit.base_diameter = median(base);
    }
    return fit;
}

std::size_t align_trunk_base(TreeGraph& tree, const TrunkFit& fit) {
    std::vector<Eigen::Vector3f> anchors;  // points of the stem axis, rising
    if (fit.foot_fitted) anchors.push_back(fit.foot_centre);
    for (const StemSlice& slice : fit.slices)
        if (slice.good && (anchors.empty() || slice.centre.z() > anchors.back().z())) anchors.push_back(slice.centre);
    if (anchors.size() < 2 || tree.size() < 2) return 0;
    std::size_t moved = 0;
    for (int node : main_axis(tree)) {
        Eigen::Vector3f& p = tree.nodes[node].position;
        if (p.z() < anchors.front().z() || p.z() > anchors.back().z()) continue;
        const auto upper =
                std::upper_bound(anchors.begin(), anchors.end(), p.z(), [](float z, const Eigen::Vector3f& a) { return z < a.z(); });
        const Eigen::Vector3f& high = upper == anchors.end() ? anchors.back() : *upper;
        const Eigen::Vector3f& low = upper == anchors.end() ? anchors.back() : *(upper - 1);
        const float t = high.z() > low.z() ? (p.z() - low.z()) / (high.z() - low.z()) : 0.0f;
        p.head<2>() = low.head<2>() + t * (high.head<2>() - low.head<2>());
        ++moved;
    }
    return moved;
}

std::size_t add_hidden_trunk(TreeGraph& tree, const Eigen::Vector3f& foot, float internode_length) {
    if (tree.empty() || !(internode_length > 0)) return 0;
    const Eigen::Vector3f root = tree.nodes[0].position;
    if (!(root.z() - foot.z() > internode_length)) return 0;
    const int added = static_cast<int>(std::ceil((root - foot).norm() / internode_length));
    TreeGraph out;
    out.origin = tree.origin;
    out.nodes.resize(static_cast<std::size_t>(added) + tree.size());
    for (int i = 0; i < added; ++i) {
        TreeNode& n = out.nodes[i];
        n.position = foot + (root - foot) * (static_cast<float>(i) / static_cast<float>(added));
        n.parent = i - 1;
        n.children = {i + 1};
    }
    for (std::size_t v = 0; v < tree.size(); ++v) {
        const TreeNode& old = tree.nodes[v];
        TreeNode& n = out.nodes[v + added];
        n.position = old.position;
        n.radius = old.radius;
        n.parent = old.parent < 0 ? added - 1 : old.parent + added;
        for (int c : old.children) n.children.push_back(c + added);
    }
    tree = std::move(out);
    return static_cast<std::size_t>(added);
}

}  // namespace treelobes
