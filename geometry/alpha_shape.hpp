// The closed surface of a point cluster: CGAL's 3D alpha shapes [Edelsbrunner and Mücke 1994]
// as Livny et al. 2011, §4.2, build their lobes (the forestry measures use them for crown
// volumes), and edge-collapse simplification of the resulting closed surface.
// Implemented in geometry/cgal_surfaces.cpp, the only file of these that includes CGAL.
//
// alpha_min is CGAL's optimal alpha for one solid component (Alpha_shape_3::find_optimal_alpha(1)):
// the smallest alpha for which every point is on the boundary or inside the shape and the
// shape is a single solid. CGAL's alpha is a squared ball radius; the paper's alpha is the
// ball radius ("alpha determining the radius of a virtual ball"), so alpha = 5 alpha_min is
// applied to the radius: CGAL alpha = alpha_factor^2 * CGAL alpha_min.
#pragma once

#include "core/triangle_mesh.hpp"

#include <Eigen/Core>

#include <span>
#include <string>

namespace treelobes {

struct AlphaShapeOptions {
    double alpha_factor = 5.0;  // alpha = alpha_factor * alpha_min (ball radii), Livny et al. 2011, §4.2
};

struct AlphaShapeResult {
    TriangleMesh mesh;              // closed 2-manifold, outward; empty when `failure` is set
    double alpha_min_radius = 0.0;  // ball radius of CGAL's optimal alpha (metres)
    double alpha_radius = 0.0;      // alpha_factor * alpha_min_radius
    std::string failure;            // why there is no shape ("all points on one plane", ...)
};

// Regularized alpha shape of `points` (local coordinates; the mesh gets origin 0, i.e. the same
// frame). Needs at least 4 points not on one plane.
AlphaShapeResult alpha_shape(std::span<const Eigen::Vector3f> points, const AlphaShapeOptions& options = {});

struct SimplifyOptions {
    double tolerance = 0.03;      // metres: collapses whose quadric error exceeds tolerance^2 stop...
    std::size_t max_faces = 400;  // ... unless the mesh still has more faces than this
    std::size_t min_faces = 8;    // never below (a tetrahedron has 4)
};

// Garland-Heckbert edge collapse of a closed 2-manifold; the result is checked to be closed
// again. Returns false and leaves `mesh` unchanged when the mesh cannot be simplified safely.
bool simplify_closed_mesh(TriangleMesh& mesh, const SimplifyOptions& options = {});

// Moves the vertices of `coarse` (a simplification of `fine`, same frame) out along their normals
// until the vertices of `fine` lie on or inside the faces nearest to them. Edge collapse cuts the
// tips and caps of a shape (a collapsed tip ends at its base, a face spans a chord); this gives
// the coarse surface back the extent of the fine one it came from. Faces are left as they are.
void inflate_to_contain(TriangleMesh& coarse, const TriangleMesh& fine);

}  // namespace treelobes
