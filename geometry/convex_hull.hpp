// Convex hull of points as a closed, outward-oriented triangle mesh (CGAL::convex_hull_3), in a
// canonical form: the same point set gives the same mesh bytes, however CGAL triangulated it.
#pragma once

#include "core/triangle_mesh.hpp"

#include <Eigen/Core>

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

}  // namespace treelobes
