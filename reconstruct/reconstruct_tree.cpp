#include "reconstruct/reconstruct_tree.hpp"

#include "core/error.hpp"
#include "core/log.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>

namespace treelobes {

namespace {

class StageClock {
public:
    explicit StageClock(std::vector<std::pair<std::string, double>>& out) : out_(out), last_(now()) {}
    void mark(const std::string& stage) {
        const auto t = now();
        out_.emplace_back(stage, std::chrono::duration<double>(t - last_).count());
        last_ = t;
    }

private:
    static std::chrono::steady_clock::time_point now() { return std::chrono::steady_clock::now(); }
    std::vector<std::pair<std::string, double>>& out_;
    std::chrono::steady_clock::time_point last_;
};

// Mean of the robust (2nd..98th percentile) extents along the two principal horizontal axes.
float crown_width(const std::vector<Eigen::Vector3f>& points) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& p : points) mean += p.head<2>().cast<double>();
    mean /= static_cast<double>(points.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const auto& p : points) {
        const Eigen::Vector2d d = p.head<2>().cast<double>() - mean;
        cov += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(cov);
    double sum = 0;
    for (int k = 0; k < 2; ++k) {
        std::vector<double> v;
        v.reserve(points.size());
        for (const auto& p : points) v.push_back((p.head<2>().cast<double>() - mean).dot(solver.eigenvectors().col(k)));
        std::sort(v.begin(), v.end());
        sum += v[v.size() * 98 / 100] - v[v.size() * 2 / 100];
    }
    return static_cast<float>(sum / 2);
}

void describe_tree(const TreeGraph& tree, TreeSummary& s) {
    s.total_length = tree.total_length();
    s.internodes = tree.size() - 1;
    s.tips = tree.tip_count();
    s.branches = 1;
    for (const auto& node : tree.nodes) s.branches += node.children.size() > 1 ? node.children.size() - 1 : 0;
    const std::vector<int> order = tree.branch_orders();
    s.max_branch_order = order.empty() ? 0 : *std::max_element(order.begin(), order.end());
}

// d_root: the user's value, else the base fit, else the breast-height fit, else a slenderness
// guess (height / 50) when the stem is not visible or no circle could be trusted.
double choose_root_diameter(const ReconstructOptions& o, const TrunkFit& trunk, bool stem_visible, TreeSummary& s) {
    if (o.root_diameter > 0) {
        s.root_diameter_source = "given";
        return o.root_diameter;
    }
    if (stem_visible && trunk.base_fitted) {
        s.root_diameter_source = "base fit";
        return trunk.base_diameter;
    }
    if (stem_visible && trunk.dbh_fitted) {
        s.root_diameter_source = "breast height fit";
        return trunk.dbh;
    }
    s.root_diameter_source = "height / 50";
    return std::max(0.01, static_cast<double>(s.height) / 50.0);
}

}  // namespace

TreeReconstruction reconstruct_tree(const PointCloud& cloud, const ReconstructOptions& o, const std::string& name) {
    TreeReconstruction out;
    TreeSummary& s = out.summary;
    StageClock clock(s.seconds);
    s.input_points = cloud.size();

    PreprocessOptions clean = o.preprocess;
    clean.table_width = skeleton_table_width(o.skeleton);  // the skeleton's kNN table comes out of the outlier query
    const Preprocessed pre = preprocess_cloud(cloud, clean, name);
    s.used_points = pre.points.size();
    s.duplicates = pre.duplicates;
    s.outliers = pre.outliers;
    s.local_outlier_test = pre.local_outlier_test;
    s.linear_fraction = pre.linear_fraction;
    s.ground_points = pre.ground;
    s.ground_removed = pre.ground_found;
    clock.mark("preprocess");

    s.quality = assess_planarity(pre.points, o.quality);
    clock.mark("quality");

    SkeletonResult sk = reconstruct_skeleton(pre.points, o.skeleton, name, pre.index.get(), pre.neighbours.get());
    s.spacing = sk.spacing;
    s.bin_width = sk.bin_width;
    s.internode_length = sk.internode_length;
    s.graph_components = sk.graph_components;
    s.bridges = sk.bridges;
    s.longest_bridge = sk.longest_bridge;
    s.detached_points = sk.detached_points;
    s.stem_visible = sk.base.stem_visible;
    if (!s.stem_visible) s.quality.flags.push_back("stem_not_visible");
    // Nodes on an axis measured by circle fits stay there (see recentre.hpp).
    s.recentred_nodes = recentre_internodes(sk.tree, pre.points, sk.point_internode, o.recentre, sk.node_on_axis);
    // Then onto the axes of cylinders fitted to longer stretches (off by default, see cylinder_axes.hpp).
    s.cylinder_axis_nodes = fit_cylinder_axes(sk.tree, pre.points, sk.point_internode, o.cylinder_axes, sk.node_on_axis);
    clock.mark("skeleton");

    out.trunk = fit_trunk(pre.points, sk.point_internode, sk.tree, o.trunk);
    for (const auto& slice : out.trunk.slices) {
        char line[200];
        std::snprintf(line, sizeof line, "stem slice at %.2f m: %zu points, centre %.3f %.3f %.3f, radius %.3f, rms %.3f, coverage %.2f%s",
                      slice.height, slice.points, slice.centre.x(), slice.centre.y(), slice.centre.z(), slice.radius, slice.rms,
                      slice.coverage, slice.good ? "" : " (rejected)");
        log_debug(line);
    }
    // The root sits on the stem axis continued from the fitted slices to the foot.
    if (sk.base.stem_visible && out.trunk.foot_fitted && (out.trunk.foot_centre - sk.tree.nodes[0].position).norm() < 1.0f)
        sk.tree.nodes[0].position = out.trunk.foot_centre;
    if (sk.base.stem_visible) align_trunk_base(sk.tree, out.trunk);
    Eigen::Vector3f foot = sk.base.position;
    if (!sk.base.stem_visible && o.hidden_stem_foot) {
        s.hidden_trunk_nodes = add_hidden_trunk(sk.tree, *o.hidden_stem_foot, sk.internode_length);
        if (s.hidden_trunk_nodes > 0) {
            foot = *o.hidden_stem_foot;
            for (int& v : sk.point_internode)
                if (v >= 0) v += static_cast<int>(s.hidden_trunk_nodes);
        }
    }
    float z_top = foot.z();
    for (const auto& p : pre.points) z_top = std::max(z_top, p.z());
    s.height = z_top - foot.z();
    s.dbh_fitted = out.trunk.dbh_fitted && s.stem_visible;
    s.dbh = s.dbh_fitted ? out.trunk.dbh : 0.0f;
    s.crown_width = crown_width(pre.points);
    const double d_root = choose_root_diameter(o, out.trunk, s.stem_visible, s);
    s.root_diameter = static_cast<float>(d_root);
    out.diameters = apply_allometry(sk.tree, d_root, o.allometry);
    describe_tree(sk.tree, s);
    if (s.quality.not_a_tree && o.warn_if_not_a_tree)
        log_warn(name + ": does not look like a tree (" + std::to_string(s.quality.planar_fraction) + " of the points lie on wide planes)");
    clock.mark("trunk and radii");

    out.point_internode.assign(cloud.size(), -1);
    out.point_geodesic.assign(cloud.size(), -1.0f);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const int p = pre.point_of_input[i];
        if (p < 0) continue;
        out.point_internode[i] = sk.point_internode[p];
        out.point_geodesic[i] = sk.point_geodesic[p];
    }
    out.skeleton = std::move(sk.tree);
    out.skeleton.origin = cloud.origin;
    return out;
}

}  // namespace treelobes
