// Forestry measures of an exported tree (CityJSON attributes, glTF extras, export summaries),
// all from the skeleton's QSM (export/qsm.hpp) and its crown.
//
// Crown: the nodes at or above the crown base (the height of the lowest fork where a lateral
// carrying at least `crown_branch_fraction` of the tree's skeleton length leaves the trunk; the
// whole tree when there is none), each widened by its radius, plus every lobe vertex. Crown
// diameter: the diameter of the circle with the area of their convex hull seen from above (as
// the tile's measures from points, forestry/measures.hpp); crown hull: their convex hull.
#pragma once

#include "core/triangle_mesh.hpp"
#include "export/tree_input.hpp"

namespace treelobes::exporting {

struct TreeMeasures {
    double height = 0;             // m, top minus base
    double dbh = 0;                // m, trunk diameter at 1.3 m (0 if the trunk is lower)
    double crown_diameter = 0;     // m
    double crown_base_height = 0;  // m above the base
    double crown_volume = 0;       // m^3 of the crown hull
    double wood_volume = 0;        // m^3, sum of the QSM cylinders
    double total_length = 0;       // m of skeleton
    std::size_t branches = 0;      // branches of order >= 1
    std::size_t lobes = 0;
    Eigen::Vector3d base{0, 0, 0};  // world coordinates
    TriangleMesh crown_hull;        // closed, origin = the tree's origin; empty if the crown spans no volume
};

TreeMeasures measure_tree(const ExportTree& tree, double crown_branch_fraction = 0.05);

}  // namespace treelobes::exporting
