// Skeleton features from a first reconstruction (Livny et al. 2011, §6.1: "an approximate first
// reconstruction"): reconstruct_skeleton on the voxel points, allometric radii (Livny et al. 2011, Eq. 1),
// then branch angles, lengths and radii by branch order, whorls, trunk form, crown asymmetry and
// the skeleton's box-counting dimension.
#include "classify/feature_groups.hpp"
#include "core/angles.hpp"
#include "reconstruct/allometry.hpp"
#include "reconstruct/skeleton.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace treelobes::classify::detail {

namespace {

// An axis: a lateral child (or the root) followed through main children to a tip.
struct Axis {
    int fork = -1;           // node it grows from (-1 for the trunk)
    std::vector<int> nodes;  // first node of the axis .. tip
    int order = 0;
    double length = 0;     // including the edge from the fork
    double angle = 0;      // degrees between its start and the parent axis at the fork
    double elevation = 0;  // degrees of its start direction above the horizontal
    double radius = 0;     // allometric radius at its base / root radius
};

// Walks up the parents from `node` until the path length reaches `distance`.
int ancestor_at(const TreeGraph& t, int node, double distance) {
    double walked = 0;
    while (t.nodes[node].parent >= 0 && walked < distance) {
        walked += t.edge_length(node);
        node = t.nodes[node].parent;
    }
    return node;
}

// Position along an axis (fork included) at path length `distance` from its start.
Eigen::Vector3f along(const TreeGraph& t, const Axis& a, double distance) {
    Eigen::Vector3f previous = a.fork >= 0 ? t.nodes[a.fork].position : t.nodes[a.nodes.front()].position;
    double walked = 0;
    for (int n : a.nodes) {
        const Eigen::Vector3f& p = t.nodes[n].position;
        walked += (p - previous).norm();
        previous = p;
        if (walked >= distance) return p;
    }
    return previous;
}

double angle_deg(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const double na = a.norm(), nb = b.norm();
    if (na <= 0 || nb <= 0) return 0.0;
    return std::acos(std::clamp(static_cast<double>(a.dot(b)) / (na * nb), -1.0, 1.0)) * kDegreesPerRadian;
}

std::vector<Axis> axes_of(const TreeGraph& t, const std::vector<int>& orders, const std::vector<float>& radius, float height) {
    std::vector<Axis> axes;
    const double reach_min = 0.05 * height;
    for (int s = 0; s < static_cast<int>(t.size()); ++s) {
        const int parent = t.nodes[s].parent;
        if (parent >= 0 && t.nodes[parent].children.front() == s) continue;  // a continuation, not a start
        Axis a;
        a.fork = parent;
        a.order = orders[s];
        for (int n = s;; n = t.nodes[n].children.front()) {
            a.nodes.push_back(n);
            a.length += t.edge_length(n);
            if (t.nodes[n].children.empty()) break;
        }
        a.radius = radius[0] > 0 ? radius[s] / radius[0] : 0.0;
        // Directions over a short stretch (half the axis, at least 5 % of the height) so that
        // skeleton noise of single internodes does not dominate the angles.
        const double reach = std::min(0.5 * a.length, std::max(reach_min, 3.0 * t.edge_length(s)));
        const Eigen::Vector3f start = parent >= 0 ? t.nodes[parent].position : t.nodes[s].position;
        const Eigen::Vector3f dir = along(t, a, reach) - start;
        a.elevation = dir.norm() > 0 ? std::asin(std::clamp(dir.z() / dir.norm(), -1.0f, 1.0f)) * kDegreesPerRadian : 0.0;
        if (parent >= 0) {
            const Eigen::Vector3f up = t.nodes[parent].position - t.nodes[ancestor_at(t, parent, reach)].position;
            a.angle = angle_deg(dir, up.norm() > 0 ? up : Eigen::Vector3f(0, 0, 1));
        }
        axes.push_back(std::move(a));
    }
    return axes;
}

struct Summary {
    double mean = 0, sd = 0, q25 = 0, q50 = 0, q75 = 0, max = 0;
};
Summary summarise(const std::vector<float>& v) {
    Summary s;
    if (v.empty()) return s;
    const Moments m = moments(v);
    s.mean = m.mean, s.sd = m.sd;
    s.q25 = quantile(v, 0.25), s.q50 = quantile(v, 0.5), s.q75 = quantile(v, 0.75);
    s.max = *std::max_element(v.begin(), v.end());
    return s;
}

double box_dimension(const std::vector<Eigen::Vector3f>& samples, float height) {
    if (samples.empty()) return 0.0;
    Eigen::Vector3f lo = samples.front();
    for (const auto& p : samples) lo = lo.cwiseMin(p);
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const int n = 5;
    for (int k = 2; k <= 6; ++k) {
        const float cell = height / std::pow(2.0f, k);
        std::unordered_set<long long> boxes;
        for (const auto& p : samples) {
            const Eigen::Vector3f q = (p - lo) / cell;
            boxes.insert((static_cast<long long>(q.x()) << 42) | (static_cast<long long>(q.y()) << 21) | static_cast<long long>(q.z()));
        }
        const double y = std::log2(static_cast<double>(boxes.size()));
        sx += k, sy += y, sxx += k * k, sxy += k * y;
    }
    const double vx = sxx - sx * sx / n;
    return vx > 0 ? (sxy - sx * sy / n) / vx : 0.0;
}

const char* kOrderNames[] = {"o1", "o2"};

}  // namespace

void describe_skeleton(Catalogue& c) {
    c.add("skel_total_length_ratio", "1", "total skeleton length / H (skeleton of the voxel points, reconstruct_skeleton)");
    c.add("skel_tip_count", "count", "skeleton tips");
    c.add("skel_axes_o1", "count", "first-order branches (axes: a lateral child followed through main children to a tip)");
    c.add("skel_axes_o2", "count", "second-order branches");
    c.add("skel_axes_o3plus", "count", "branches of order 3 and higher");
    for (const char* o : kOrderNames) {
        const std::string order = o[1] == '1' ? "first-order" : "second-order";
        c.add(std::string("skel_angle_") + o + "_mean", "deg",
              "mean branching angle of " + order +
                      " branches: between the branch start (over max(5 % H, 3 internodes), at most half "
                      "its length) and the parent axis before the fork");
        c.add(std::string("skel_angle_") + o + "_sd", "deg", "standard deviation of those angles");
        c.add(std::string("skel_angle_") + o + "_q25", "deg", "25 % quantile of those angles");
        c.add(std::string("skel_angle_") + o + "_q50", "deg", "median of those angles");
        c.add(std::string("skel_angle_") + o + "_q75", "deg", "75 % quantile of those angles");
    }
    for (const char* o : kOrderNames) {
        const std::string order = o[1] == '1' ? "first-order" : "second-order";
        c.add(std::string("skel_elevation_") + o + "_mean", "deg", "mean elevation above the horizontal of " + order + " branch starts");
        c.add(std::string("skel_elevation_") + o + "_sd", "deg", "standard deviation of those elevations");
        c.add(std::string("skel_elevation_") + o + "_q50", "deg", "median of those elevations");
    }
    for (const char* o : kOrderNames) {
        const std::string order = o[1] == '1' ? "first-order" : "second-order";
        c.add(std::string("skel_length_") + o + "_mean", "1", "mean length / H of " + order + " branches (with the edge from the fork)");
        c.add(std::string("skel_length_") + o + "_sd", "1", "standard deviation of those lengths / H");
        c.add(std::string("skel_length_") + o + "_max", "1", "longest " + order + " branch / H");
    }
    for (const char* o : kOrderNames) {
        const std::string order = o[1] == '1' ? "first-order" : "second-order";
        c.add(std::string("skel_radius_") + o + "_mean", "1",
              "mean allometric radius at the base of " + order + " branches / root radius (Livny et al. 2011, Eq. 1, gamma 1.5)");
        c.add(std::string("skel_radius_") + o + "_sd", "1", "standard deviation of those radius ratios");
    }
    c.add("skel_length_fraction_o0", "1", "fraction of the skeleton length on the trunk (order 0)");
    c.add("skel_length_fraction_o1", "1", "fraction on first-order branches");
    c.add("skel_length_fraction_o2", "1", "fraction on second-order branches");
    c.add("skel_length_fraction_o3plus", "1", "fraction on branches of order 3 and higher");
    c.add("skel_max_order", "count", "highest branch order");
    c.add("skel_first_branch_height", "1", "height of the lowest first-order fork on the trunk / H");
    c.add("skel_whorl_count", "count",
          "whorls: first-order forks on the trunk grouped when less than max(2 % H, 2 voxels) apart in height");
    c.add("skel_whorl_spacing_mean", "1", "mean height step between consecutive whorls / H");
    c.add("skel_whorl_spacing_cv", "1", "coefficient of variation of the whorl spacing");
    c.add("skel_branches_per_whorl", "1", "first-order branches on the trunk per whorl");
    c.add("skel_trunk_length_ratio", "1", "length of the trunk axis (root through main children) / H");
    c.add("skel_trunk_tortuosity", "1", "trunk axis length / distance from root to trunk tip");
    c.add("skel_trunk_lean", "deg", "angle from the vertical of the chord from the root to the trunk point at a third of its length");
    c.add("skel_tip_offset_ratio", "1", "crown asymmetry: horizontal distance from the axis to the centroid of the tips / R");
    c.add("skel_tip_eigen_ratio", "1", "smaller / larger eigenvalue of the tips' horizontal covariance");
    c.add("skel_tip_height_q10", "1", "10 % quantile of tip heights / H");
    c.add("skel_tip_height_q50", "1", "median tip height / H");
    c.add("skel_tip_height_q90", "1", "90 % quantile of tip heights / H");
    c.add("skel_tip_low_fraction", "1", "fraction of tips below half the height");
    c.add("skel_path_ratio_mean", "1", "mean over tips of path length from the root / straight distance");
    c.add("skel_path_length_mean", "1", "mean path length from the root to the tips / H");
    c.add("skel_boxcount_dimension", "1", "box-counting dimension of the skeleton (edges sampled every half voxel, sizes H/4 .. H/64)");
}

void skip_skeleton(FeatureSink& out) {
    const auto& catalogue = feature_catalogue();
    for (std::size_t i = out.size(); i < catalogue.size() && catalogue[i].group == "skeleton"; ++i) out.add(catalogue[i].name, 0.0);
}

namespace {

// Per branch order: counts, angles, elevations, lengths and radii of the axes, the share of the
// skeleton's length at each order.
void add_axis_features(const TreeGraph& t, const std::vector<Axis>& axes, double h, FeatureSink& out) {
    const double total = t.total_length();
    std::vector<float> angle[2], elevation[2], length[2], rad[2];
    double by_order[4] = {0, 0, 0, 0};
    int count[3] = {0, 0, 0}, max_order = 0;
    for (const auto& a : axes) {
        by_order[std::min(a.order, 3)] += a.length;
        max_order = std::max(max_order, a.order);
        if (a.order >= 1) ++count[std::min(a.order, 3) - 1];
        if (a.order < 1 || a.order > 2) continue;
        const int o = a.order - 1;
        angle[o].push_back(static_cast<float>(a.angle));
        elevation[o].push_back(static_cast<float>(a.elevation));
        length[o].push_back(static_cast<float>(a.length / h));
        rad[o].push_back(static_cast<float>(a.radius));
    }
    out.add("skel_total_length_ratio", total / h);
    out.add("skel_tip_count", static_cast<double>(t.tip_count()));
    out.add("skel_axes_o1", count[0]);
    out.add("skel_axes_o2", count[1]);
    out.add("skel_axes_o3plus", count[2]);
    for (int o = 0; o < 2; ++o) {
        const Summary s = summarise(angle[o]);
        const std::string p = std::string("skel_angle_") + kOrderNames[o];
        out.add(p + "_mean", s.mean), out.add(p + "_sd", s.sd), out.add(p + "_q25", s.q25), out.add(p + "_q50", s.q50),
                out.add(p + "_q75", s.q75);
    }
    for (int o = 0; o < 2; ++o) {
        const Summary s = summarise(elevation[o]);
        const std::string p = std::string("skel_elevation_") + kOrderNames[o];
        out.add(p + "_mean", s.mean), out.add(p + "_sd", s.sd), out.add(p + "_q50", s.q50);
    }
    for (int o = 0; o < 2; ++o) {
        const Summary s = summarise(length[o]);
        const std::string p = std::string("skel_length_") + kOrderNames[o];
        out.add(p + "_mean", s.mean), out.add(p + "_sd", s.sd), out.add(p + "_max", s.max);
    }
    for (int o = 0; o < 2; ++o) {
        const Summary s = summarise(rad[o]);
        const std::string p = std::string("skel_radius_") + kOrderNames[o];
        out.add(p + "_mean", s.mean), out.add(p + "_sd", s.sd);
    }
    out.add("skel_length_fraction_o0", total > 0 ? by_order[0] / total : 0.0);
    out.add("skel_length_fraction_o1", total > 0 ? by_order[1] / total : 0.0);
    out.add("skel_length_fraction_o2", total > 0 ? by_order[2] / total : 0.0);
    out.add("skel_length_fraction_o3plus", total > 0 ? by_order[3] / total : 0.0);
    out.add("skel_max_order", max_order);
}

// Whorls along the trunk: first-order branches leaving the trunk at about the same height.
void add_whorl_features(const TreeFrame& f, const TreeGraph& t, const std::vector<Axis>& axes, const std::vector<int>& orders,
                        FeatureSink& out) {
    const double h = f.height;
    std::vector<float> trunk_forks;
    for (const auto& a : axes)
        if (a.order == 1 && orders[a.fork] == 0) trunk_forks.push_back(t.nodes[a.fork].position.z());
    std::sort(trunk_forks.begin(), trunk_forks.end());
    std::vector<float> whorls;  // mean height of each whorl
    std::vector<int> members;
    const float gap = std::max(0.02f * f.height, 2 * f.voxel);
    for (std::size_t i = 0; i < trunk_forks.size(); ++i) {
        if (i == 0 || trunk_forks[i] - trunk_forks[i - 1] >= gap) whorls.push_back(0), members.push_back(0);
        whorls.back() += trunk_forks[i], ++members.back();
    }
    for (std::size_t w = 0; w < whorls.size(); ++w) whorls[w] /= static_cast<float>(members[w]);
    std::vector<float> spacing;
    for (std::size_t w = 1; w < whorls.size(); ++w) spacing.push_back(whorls[w] - whorls[w - 1]);
    const Moments ms = moments(spacing);
    out.add("skel_first_branch_height", trunk_forks.empty() ? 0.0 : trunk_forks.front() / h);
    out.add("skel_whorl_count", static_cast<double>(whorls.size()));
    out.add("skel_whorl_spacing_mean", ms.mean / h);
    out.add("skel_whorl_spacing_cv", ms.mean > 0 ? ms.sd / ms.mean : 0.0);
    out.add("skel_branches_per_whorl", whorls.empty() ? 0.0 : static_cast<double>(trunk_forks.size()) / whorls.size());
}

// Trunk form: the axis starting at the root.
void add_trunk_features(const TreeGraph& t, const Axis& trunk, double h, FeatureSink& out) {
    const Eigen::Vector3f root = t.nodes[0].position;
    const double chord = (t.nodes[trunk.nodes.back()].position - root).norm();
    const Eigen::Vector3f third = along(t, trunk, trunk.length / 3) - root;
    out.add("skel_trunk_length_ratio", trunk.length / h);
    out.add("skel_trunk_tortuosity", chord > 0 ? trunk.length / chord : 1.0);
    out.add("skel_trunk_lean", angle_deg(third, Eigen::Vector3f(0, 0, 1)));
}

// Tips: asymmetry, heights, paths.
void add_tip_features(const TreeFrame& f, const TreeGraph& t, FeatureSink& out) {
    const double h = f.height;
    const Eigen::Vector3f root = t.nodes[0].position;
    std::vector<double> path(t.size(), 0.0);
    for (int n : t.preorder())
        if (t.nodes[n].parent >= 0) path[n] = path[t.nodes[n].parent] + t.edge_length(n);
    std::vector<Eigen::Vector3f> tips;
    std::vector<float> tip_height, path_ratio, path_length;
    for (int n = 0; n < static_cast<int>(t.size()); ++n) {
        if (!t.nodes[n].children.empty()) continue;
        const Eigen::Vector3f& p = t.nodes[n].position;
        tips.push_back(p);
        tip_height.push_back(static_cast<float>(p.z() / h));
        const double straight = (p - root).norm();
        if (straight > 0) path_ratio.push_back(static_cast<float>(path[n] / straight));
        path_length.push_back(static_cast<float>(path[n] / h));
    }
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    for (const auto& p : tips) centroid += p.head<2>().cast<double>();
    centroid /= static_cast<double>(tips.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const auto& p : tips) cov += (p.head<2>().cast<double>() - centroid) * (p.head<2>().cast<double>() - centroid).transpose();
    const Eigen::Vector2d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvalues();
    out.add("skel_tip_offset_ratio", centroid.norm() / f.crown_radius);
    out.add("skel_tip_eigen_ratio", ev(1) > 0 ? ev(0) / ev(1) : 0.0);
    out.add("skel_tip_height_q10", quantile(tip_height, 0.1));
    out.add("skel_tip_height_q50", quantile(tip_height, 0.5));
    out.add("skel_tip_height_q90", quantile(tip_height, 0.9));
    out.add("skel_tip_low_fraction",
            std::count_if(tip_height.begin(), tip_height.end(), [](float v) { return v < 0.5f; }) / static_cast<double>(tips.size()));
    out.add("skel_path_ratio_mean", moments(path_ratio).mean);
    out.add("skel_path_length_mean", moments(path_length).mean);
}

// Box-counting dimension of the skeleton, sampled every half voxel along its internodes.
void add_boxcount_feature(const TreeFrame& f, const TreeGraph& t, FeatureSink& out) {
    std::vector<Eigen::Vector3f> samples;
    for (int n = 1; n < static_cast<int>(t.size()); ++n) {
        const Eigen::Vector3f a = t.nodes[t.nodes[n].parent].position, b = t.nodes[n].position;
        const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() / (0.5f * f.voxel))));
        for (int s = 0; s < steps; ++s) samples.push_back(a + (b - a) * (static_cast<float>(s) / steps));
    }
    out.add("skel_boxcount_dimension", box_dimension(samples, f.height));
}

}  // namespace

void compute_skeleton(const TreeFrame& f, FeatureSink& out) {
    // Bins and internodes tied to the voxel size (not to the measured spacing) so that a thinned
    // scan yields the same coarse skeleton: main branches are what tells species apart.
    SkeletonOptions options;
    options.bin_width = std::clamp(0.25f * f.crown_radius, 2 * f.voxel, 4 * f.voxel);  // narrow crowns need finer bins
    options.internode_length = options.bin_width;
    SkeletonResult result = reconstruct_skeleton(f.points, options, "", f.index.get(), f.neighbours.get());
    TreeGraph& t = result.tree;
    if (t.size() < 2) {
        skip_skeleton(out);
        return;
    }
    const float root_diameter = f.trunk_diameter > 0 ? f.trunk_diameter : f.height / 50;
    apply_allometry(t, root_diameter);
    std::vector<float> radius;
    for (const auto& n : t.nodes) radius.push_back(n.radius);
    const auto orders = t.branch_orders();
    const auto axes = axes_of(t, orders, radius, f.height);
    add_axis_features(t, axes, f.height, out);
    add_whorl_features(f, t, axes, orders, out);
    add_trunk_features(t, axes.front(), f.height, out);
    add_tip_features(f, t, out);
    add_boxcount_feature(f, t, out);
}

}  // namespace treelobes::classify::detail
