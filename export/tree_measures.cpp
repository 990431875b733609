#include "export/tree_measures.hpp"

#include "geometry/convex_hull.hpp"
#include "export/qsm.hpp"

#include <algorithm>

namespace treelobes::exporting {

namespace {

// Height (local z) of the lowest trunk node with a lateral child whose subtree holds at least
// `min_length` of skeleton; +infinity when no lateral is that large.
float crown_base_z(const TreeGraph& tree, float min_length) {
    const std::vector<float> below = tree.subtree_lengths();
    float lowest = std::numeric_limits<float>::infinity();
    for (int node = 0; node >= 0 && !tree.nodes[node].children.empty(); node = tree.nodes[node].children.front()) {
        const auto& children = tree.nodes[node].children;
        for (std::size_t k = 1; k < children.size(); ++k)
            if (below[children[k]] + tree.edge_length(children[k]) >= min_length) lowest = std::min(lowest, tree.nodes[node].position.z());
    }
    return lowest;
}

std::vector<Eigen::Vector3f> crown_points(const ExportTree& tree, float base_z) {
    std::vector<Eigen::Vector3f> points;
    for (const auto& node : tree.skeleton.nodes) {
        if (node.position.z() < base_z) continue;
        const float r = node.radius;
        points.push_back(node.position);
        for (int axis = 0; axis < 3; ++axis)
            for (float sign : {-1.0f, 1.0f}) points.push_back(node.position + sign * r * Eigen::Vector3f::Unit(axis));
    }
    for (const auto& lobe : tree.lobes) {
        const Eigen::Vector3f offset = (lobe.origin - tree.skeleton.origin).cast<float>();
        for (const auto& v : lobe.vertices) points.push_back(v + offset);
    }
    return points;
}

}  // namespace

TreeMeasures measure_tree(const ExportTree& tree, double crown_branch_fraction) {
    TreeMeasures m;
    const QsmModel qsm = qsm_from_tree(tree.skeleton, tree.name);
    const QsmTreeMeasures q = measure_qsm(qsm);
    m.height = q.height;
    m.dbh = q.dbh;
    m.wood_volume = q.total_volume;
    m.total_length = q.total_length;
    m.branches = q.branches;
    m.lobes = tree.lobes.size();
    m.base = qsm.cylinders.empty() ? tree.skeleton.origin + tree.skeleton.nodes.front().position.cast<double>() : q.base;
    const float base_z = crown_base_z(tree.skeleton, static_cast<float>(crown_branch_fraction * tree.skeleton.total_length()));
    const float lowest = std::isfinite(base_z) ? base_z : -std::numeric_limits<float>::infinity();
    const std::vector<Eigen::Vector3f> points = crown_points(tree, lowest);
    if (!points.empty()) {
        Eigen::Vector3f lo = points.front(), hi = points.front();
        for (const auto& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
        m.crown_diameter = equal_area_diameter(ring_area(projected_hull(points)));
        m.crown_base_height = std::max(0.0, tree.skeleton.origin.z() + lo.z() - m.base.z());
    }
    m.crown_hull = convex_hull(points, tree.skeleton.origin);
    m.crown_volume = m.crown_hull.signed_volume();
    return m;
}

}  // namespace treelobes::exporting
