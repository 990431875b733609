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

// The convex hull of the points seen from above: its corners (x, y), counter-clockwise as
// GeoJSON's exterior rings go, the first not repeated at the end. A crown's outline. Empty for
// fewer than 3 points or collinear ones.
std::vector<Eigen::Vector2d> projected_hull(std::span<const Eigen::Vector3f> points);

// Area enclosed by a ring of corners (either orientation; square metres): of projected_hull, a
// crown's projected area. 0 for fewer than 3 corners.
double ring_area(std::span<const Eigen::Vector2d> ring);

// Diameter of the circle of the given area: the crown diameter of every treelobes measure (the
// tile's trees.csv from points, the exports from a skeleton and its lobes), so that one tree
// gets one crown diameter whichever output a user reads.
double equal_area_diameter(double area);

}  // namespace treelobes
