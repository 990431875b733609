// Convex hull of points as a closed, outward-oriented triangle mesh (CGAL::convex_hull_3), in a
// canonical form: the same point set gives the same mesh bytes, however CGAL triangulated it.
#pragma once

#include "core/triangle_mesh.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace treelobes {

// Points and result share `origin`. Empty mesh when the points span no volume (fewer than four
// points, or all of them on one plane).
//
// Why canonical: CGAL splits a planar hull facet with more than three corners (common here: the
// crowns are hulls of skeleton nodes widened along the axes) into triangles in an order that
// depends on where its handles sit in memory, so the same input gave different diagonals from one
// call to the next. The hull's planar facets and their strictly convex corners are unique, so they
// are found again (coplanar neighbours joined with CGAL's exact orientation test) and each facet is
// fanned from its lexicographically smallest corner; vertices are sorted by coordinates.
TriangleMesh convex_hull(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3d& origin);

// Area of the convex hull of the points seen from above (x, y; square metres): a crown's
// projected area. 0 for fewer than 3 points or collinear ones.
double projected_hull_area(std::span<const Eigen::Vector3f> points);

// Diameter of the circle of the given area: the crown diameter of every treelobes measure (the
// tile's trees.csv from points, the exports from a skeleton and its lobes), so that one tree
// gets one crown diameter whichever output a user reads.
double equal_area_diameter(double area);

}  // namespace treelobes
