// Convex hull of points as a closed, outward-oriented triangle mesh (CGAL::convex_hull_3).
#pragma once

#include "core/triangle_mesh.hpp"

#include <Eigen/Core>

#include <vector>

namespace treelobes::exporting {

// Points and result share `origin`. Empty mesh when the points span no volume (fewer than four
// points, or all of them on one plane).
TriangleMesh convex_hull(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3d& origin);

}  // namespace treelobes::exporting
