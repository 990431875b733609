// QSM tables from a skeleton (one cylinder per internode) and the measures TreeQSM reports
// for them (Raumonen et al. 2013; the `branch` and `treedata` outputs of TreeQSM 2.x).
#pragma once

#include "core/qsm_io.hpp"
#include "core/tree_graph.hpp"

#include <filesystem>
#include <vector>

namespace treelobes::exporting {

// One cylinder per edge parent -> child, in original coordinates (origin added). Cylinders are
// listed branch by branch (trunk first; branches numbered in depth-first order of their first
// internode, main child first), each branch from base to tip, so a parent always precedes its
// children. Radius: the mean of the two end radii for a continuation; a lateral's first
// internode takes its own (child) radius, since the fork node carries the parent's thickness.
// The tree is validated first (Error(InvalidInput) naming `context` if it is not one rooted tree).
QsmModel qsm_from_tree(const TreeGraph& tree, const std::string& context = "skeleton");

// TreeQSM's treedata quantities (volumes in cubic metres here; the table file shows litres).
struct QsmTreeMeasures {
    double total_volume = 0, trunk_volume = 0, branch_volume = 0;  // m^3
    double height = 0;                                             // highest cylinder end minus the lowest trunk start (m)
    double trunk_length = 0, branch_length = 0, total_length = 0;  // m
    std::size_t branches = 0;                                      // branches of order >= 1
    int max_branch_order = 0;
    double dbh = 0;                 // diameter of the trunk cylinder at 1.3 m above the base (m); 0 if the trunk is lower
    Eigen::Vector3d base{0, 0, 0};  // start of the lowest trunk cylinder
};
QsmTreeMeasures measure_qsm(const QsmModel& model);

// One row of TreeQSM's branch table.
struct QsmBranch {
    int id = 0;  // branch id of the cylinders (0-based)
    int order = 0;
    int parent = -1;      // branch id of the parent branch, -1 for the trunk
    double volume = 0;    // m^3
    double length = 0;    // m
    double angle = 0;     // degrees between the branch's first cylinder and its parent cylinder
    double height = 0;    // m above the base, at the branch's first cylinder start
    double azimuth = 0;   // degrees, atan2(y, x) of the first cylinder's axis
    double diameter = 0;  // m, of the first cylinder
};
std::vector<QsmBranch> qsm_branches(const QsmModel& model);

// "<stem>_branch.txt" and "<stem>_tree.txt" beside a cylinder file, and writing all three.
std::filesystem::path qsm_branch_table_path(const std::filesystem::path& cylinder_file);
std::filesystem::path qsm_tree_table_path(const std::filesystem::path& cylinder_file);
void write_qsm_branch_table(const QsmModel& model, const std::filesystem::path& path);
void write_qsm_tree_table(const QsmModel& model, const std::filesystem::path& path);

}  // namespace treelobes::exporting
