#include "export/qsm.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>

namespace fs = std::filesystem;

namespace treelobes::exporting {

namespace {

constexpr double kBreastHeight = 1.3;  // metres above the base
constexpr double kLitresPerCubicMetre = 1000.0;

double degrees(double radians) { return radians * 180.0 / std::numbers::pi; }

// Branch (axis) of every non-root node: a node continues its parent's branch when it is the
// parent's main child (and the parent is not the root); every other node starts a branch.
// Branch ids follow the depth-first order of their first node, so the trunk is branch 0.
std::vector<int> branch_of_nodes(const TreeGraph& tree, const std::vector<int>& preorder) {
    std::vector<int> branch(tree.size(), -1);
    int next = 0;
    for (int node : preorder) {
        if (node == 0) continue;
        const int parent = tree.nodes[node].parent;
        const bool continues = parent != 0 && tree.nodes[parent].children.front() == node;
        branch[node] = continues ? branch[parent] : next++;
    }
    return branch;
}

}  // namespace

QsmModel qsm_from_tree(const TreeGraph& tree, const std::string& context) {
    tree.validate(context);
    QsmModel model;
    if (tree.size() < 2) return model;
    const std::vector<int> preorder = tree.preorder();
    const std::vector<int> orders = tree.branch_orders();
    const std::vector<int> branch = branch_of_nodes(tree, preorder);

    // Cylinders sorted by (branch, position along it); preorder visits a branch base to tip.
    std::vector<std::vector<int>> nodes_of_branch;
    for (int node : preorder) {
        if (node == 0) continue;
        if (static_cast<std::size_t>(branch[node]) >= nodes_of_branch.size()) nodes_of_branch.resize(branch[node] + 1);
        nodes_of_branch[branch[node]].push_back(node);
    }
    std::vector<int> cylinder_of(tree.size(), -1);
    int index = 0;
    for (const auto& nodes : nodes_of_branch)
        for (int node : nodes) cylinder_of[node] = index++;
    model.cylinders.resize(static_cast<std::size_t>(index));
    for (std::size_t b = 0; b < nodes_of_branch.size(); ++b)
        for (std::size_t k = 0; k < nodes_of_branch[b].size(); ++k) {
            const int node = nodes_of_branch[b][k];
            const TreeNode& n = tree.nodes[node];
            const TreeNode& p = tree.nodes[n.parent];
            QsmCylinder& c = model.cylinders[cylinder_of[node]];
            c.start = tree.origin + p.position.cast<double>();
            const Eigen::Vector3d end = tree.origin + n.position.cast<double>();
            c.length = (end - c.start).norm();
            const bool continuation = k > 0 || (n.parent == 0 && b == 0);
            if (c.length > 0)
                c.axis = (end - c.start) / c.length;
            else if (n.parent != 0)
                c.axis = model.cylinders[cylinder_of[n.parent]].axis;  // a zero-length internode keeps its parent's direction
            c.radius = continuation ? 0.5 * (static_cast<double>(p.radius) + n.radius) : static_cast<double>(n.radius);
            c.unmodified_radius = c.radius;
            c.parent = n.parent == 0 ? -1 : cylinder_of[n.parent];
            c.extension = n.children.empty() ? -1 : cylinder_of[n.children.front()];
            c.branch = static_cast<int>(b);
            c.branch_order = orders[node];
            c.position_in_branch = static_cast<int>(k);
        }
    model.derive_segments();
    return model;
}

QsmTreeMeasures measure_qsm(const QsmModel& model) {
    QsmTreeMeasures m;
    if (model.cylinders.empty()) return m;
    double base_z = std::numeric_limits<double>::max(), top_z = std::numeric_limits<double>::lowest();
    for (const auto& c : model.cylinders) {
        if (c.branch_order == 0 && c.start.z() < base_z) {
            base_z = c.start.z();
            m.base = c.start;
        }
        top_z = std::max({top_z, c.start.z(), c.end().z()});
    }
    if (base_z == std::numeric_limits<double>::max()) {  // no order-0 cylinder: the lowest start is the base
        for (const auto& c : model.cylinders)
            if (c.start.z() < base_z) base_z = c.start.z(), m.base = c.start;
    }
    m.height = top_z - base_z;
    std::map<int, bool> branch_ids;
    for (const auto& c : model.cylinders) {
        const double v = c.volume();
        m.total_volume += v;
        m.total_length += c.length;
        if (c.branch_order == 0) {
            m.trunk_volume += v;
            m.trunk_length += c.length;
            const double z0 = c.start.z() - base_z, z1 = c.end().z() - base_z;
            if (m.dbh == 0 && std::min(z0, z1) <= kBreastHeight && std::max(z0, z1) >= kBreastHeight) m.dbh = 2 * c.radius;
        } else {
            m.branch_volume += v;
            m.branch_length += c.length;
            branch_ids[c.branch] = true;
        }
        m.max_branch_order = std::max(m.max_branch_order, c.branch_order);
    }
    m.branches = branch_ids.size();
    return m;
}

std::vector<QsmBranch> qsm_branches(const QsmModel& model) {
    std::map<int, QsmBranch> by_id;
    std::map<int, int> first_cylinder;
    for (std::size_t i = 0; i < model.cylinders.size(); ++i) {
        const auto& c = model.cylinders[i];
        auto [it, fresh] = by_id.try_emplace(c.branch);
        QsmBranch& b = it->second;
        b.id = c.branch;
        b.volume += c.volume();
        b.length += c.length;
        auto [first, none_yet] = first_cylinder.try_emplace(c.branch, static_cast<int>(i));
        if (!none_yet && c.position_in_branch < model.cylinders[first->second].position_in_branch) first->second = static_cast<int>(i);
    }
    const double base_z = measure_qsm(model).base.z();
    std::vector<QsmBranch> rows;
    for (auto& [id, b] : by_id) {
        const QsmCylinder& first = model.cylinders[first_cylinder[id]];
        b.order = first.branch_order;
        b.height = first.start.z() - base_z;
        b.diameter = 2 * first.radius;
        b.azimuth = degrees(std::atan2(first.axis.y(), first.axis.x()));
        if (first.parent >= 0) {
            const QsmCylinder& parent = model.cylinders[first.parent];
            b.parent = parent.branch;
            b.angle = degrees(std::acos(std::clamp(first.axis.dot(parent.axis), -1.0, 1.0)));
        }
        rows.push_back(b);
    }
    return rows;
}

fs::path qsm_branch_table_path(const fs::path& cylinder_file) {
    return cylinder_file.parent_path() / (cylinder_file.stem().string() + "_branch.txt");
}

fs::path qsm_tree_table_path(const fs::path& cylinder_file) {
    return cylinder_file.parent_path() / (cylinder_file.stem().string() + "_tree.txt");
}

void write_qsm_branch_table(const QsmModel& model, const fs::path& path) {
    std::string out = "branch\torder\tparent\tvolume_L\tlength_m\tangle_deg\theight_m\tazimuth_deg\tdiameter_m\n";
    char line[320];
    for (const QsmBranch& b : qsm_branches(model)) {
        std::snprintf(line, sizeof line, "%d\t%d\t%d\t%.6g\t%.6g\t%.4g\t%.6g\t%.4g\t%.6g\n", b.id + 1, b.order, b.parent + 1,
                      b.volume * kLitresPerCubicMetre, b.length, b.angle, b.height, b.azimuth == 0 ? 0.0 : b.azimuth, b.diameter);
        out += line;
    }
    write_file_atomically(path, out);
}

void write_qsm_tree_table(const QsmModel& model, const fs::path& path) {
    const QsmTreeMeasures m = measure_qsm(model);
    std::string out = "quantity\tvalue\tunit\n";
    char line[160];
    const auto row = [&](const char* name, double value, const char* unit) {
        std::snprintf(line, sizeof line, "%s\t%.9g\t%s\n", name, value, unit);
        out += line;
    };
    row("TotalVolume", m.total_volume * kLitresPerCubicMetre, "L");
    row("TrunkVolume", m.trunk_volume * kLitresPerCubicMetre, "L");
    row("BranchVolume", m.branch_volume * kLitresPerCubicMetre, "L");
    row("TreeHeight", m.height, "m");
    row("TrunkLength", m.trunk_length, "m");
    row("BranchLength", m.branch_length, "m");
    row("TotalLength", m.total_length, "m");
    row("NumberBranches", static_cast<double>(m.branches), "1");
    row("MaxBranchOrder", m.max_branch_order, "1");
    row("DBHcyl", m.dbh, "m");
    row("NumberCylinders", static_cast<double>(model.cylinders.size()), "1");
    write_file_atomically(path, out);
}

}  // namespace treelobes::exporting
