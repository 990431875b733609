// The closed surfaces built with CGAL, in one translation unit (CGAL is header-only and slow to
// compile; DESIGN.md keeps third-party types inside .cpp files):
//   - alpha shapes of point clusters: the lobes (Livny et al. 2011, §4.2) and crown volumes
//     (geometry/alpha_shape.hpp),
//   - edge-collapse simplification of closed surfaces, and their inflation back to the extent
//     of the surface they came from (geometry/alpha_shape.hpp),
//   - AABB-tree distances from points to a mesh (geometry/mesh_distance.hpp).
// The kernel is Exact_predicates_inexact_constructions: exact orientation and in-sphere tests
// keep the Delaunay triangulation valid on scanner data with duplicates and coplanar runs.
#include "core/parallel.hpp"
#include "geometry/alpha_shape.hpp"
#include "geometry/closed_mesh.hpp"
#include "geometry/mesh_distance.hpp"

#include "core/error.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Alpha_shape_3.h>
#include <CGAL/Alpha_shape_cell_base_3.h>
#include <CGAL/Alpha_shape_vertex_base_3.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_placement.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <tbb/blocked_range.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace treelobes {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;

// ---- alpha shapes -------------------------------------------------------------------------

using AlphaVertex = CGAL::Alpha_shape_vertex_base_3<K>;
using AlphaCell = CGAL::Alpha_shape_cell_base_3<K>;
using AlphaTds = CGAL::Triangulation_data_structure_3<AlphaVertex, AlphaCell>;
using Delaunay = CGAL::Delaunay_triangulation_3<K, AlphaTds, CGAL::Fast_location>;
using AlphaShape3 = CGAL::Alpha_shape_3<Delaunay>;

Eigen::Vector3f to_eigen(const Point& p) { return {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())}; }

// The regular facets (between a solid and an empty cell) as triangles seen from the solid
// cell's outside: the opposite vertex of the solid cell lies behind each triangle. The
// triangles are sorted by their coordinates and vertices numbered in that order, so the mesh
// does not depend on the order of CGAL's cell container or on vertex addresses (the same
// cluster always gives the same bytes in the .tlobe file).
TriangleMesh regular_facets(const AlphaShape3& shape) {
    std::vector<AlphaShape3::Facet> facets;
    shape.get_alpha_shape_facets(std::back_inserter(facets), AlphaShape3::REGULAR);
    using Key = std::array<double, 3>;
    auto key = [](const Point& p) { return Key{p.x(), p.y(), p.z()}; };
    std::vector<std::array<Key, 3>> triangles;
    triangles.reserve(facets.size());
    for (auto [cell, i] : facets) {
        if (shape.classify(cell) != AlphaShape3::INTERIOR) {
            const auto other = cell->neighbor(i);
            i = other->index(cell);
            cell = other;
        }
        const Point& a = cell->vertex((i + 1) & 3)->point();
        Point b = cell->vertex((i + 2) & 3)->point();
        Point c = cell->vertex((i + 3) & 3)->point();
        // Exact orientation test: the solid cell's fourth vertex must be below the triangle.
        if (CGAL::orientation(a, b, c, cell->vertex(i)->point()) == CGAL::POSITIVE) std::swap(b, c);
        std::array<Key, 3> t{key(a), key(b), key(c)};
        std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());  // keeps the orientation
        triangles.push_back(t);
    }
    std::sort(triangles.begin(), triangles.end());
    TriangleMesh mesh;
    std::map<Key, int> index;
    for (const auto& t : triangles) {
        std::array<int, 3> f{};
        for (int k = 0; k < 3; ++k) {
            const auto [it, fresh] = index.emplace(t[k], static_cast<int>(mesh.vertices.size()));
            if (fresh) mesh.vertices.emplace_back(static_cast<float>(t[k][0]), static_cast<float>(t[k][1]), static_cast<float>(t[k][2]));
            f[k] = it->second;
        }
        mesh.faces.push_back(f);
    }
    return mesh;
}

// ---- simplification -----------------------------------------------------------------------

using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace SMS = CGAL::Surface_mesh_simplification;

// Collapses continue while the cheapest collapse moves the surface by at most `tolerance`
// (quadric error in squared metres) or the mesh has more edges than allowed; never below min.
struct ToleranceOrCountStop {
    double max_cost;
    std::size_t max_edges;
    std::size_t min_edges;
    template <typename F, typename Profile>
    bool operator()(const F& cost, const Profile&, std::size_t, std::size_t edges) const {
        if (edges <= min_edges) return true;
        return edges <= max_edges && static_cast<double>(cost) > max_cost;
    }
};

bool to_surface_mesh(const TriangleMesh& mesh, SurfaceMesh& out) {
    std::vector<SurfaceMesh::Vertex_index> vertex;
    vertex.reserve(mesh.vertices.size());
    for (const auto& p : mesh.vertices) vertex.push_back(out.add_vertex(Point(p.x(), p.y(), p.z())));
    for (const auto& f : mesh.faces)
        if (out.add_face(vertex[f[0]], vertex[f[1]], vertex[f[2]]) == SurfaceMesh::null_face()) return false;
    return true;
}

TriangleMesh from_surface_mesh(const SurfaceMesh& sm, const Eigen::Vector3d& origin) {
    TriangleMesh mesh;
    mesh.origin = origin;
    std::map<SurfaceMesh::Vertex_index, int> index;
    for (auto v : sm.vertices()) {
        index.emplace(v, static_cast<int>(mesh.vertices.size()));
        mesh.vertices.push_back(to_eigen(sm.point(v)));
    }
    for (auto f : sm.faces()) {
        std::array<int, 3> tri{};
        int k = 0;
        for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) tri[k++] = index.at(v);
        mesh.faces.push_back(tri);
    }
    return mesh;
}

// ---- distances ------------------------------------------------------------------------------

using Triangle = K::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, TriangleIterator>;
using AabbTree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

}  // namespace

AlphaShapeResult alpha_shape(std::span<const Eigen::Vector3f> points, const AlphaShapeOptions& options) {
    if (!(options.alpha_factor >= 1.0) || !std::isfinite(options.alpha_factor))
        throw Error::usage("alpha shape: --alpha-factor must be >= 1, got " + std::to_string(options.alpha_factor));
    AlphaShapeResult result;
    if (points.size() < 4) {
        result.failure = "fewer than 4 points";
        return result;
    }
    std::vector<Point> input;
    input.reserve(points.size());
    for (const auto& p : points) input.emplace_back(p.x(), p.y(), p.z());
    AlphaShape3 shape(input.begin(), input.end(), 0, AlphaShape3::REGULARIZED);
    if (shape.dimension() < 3) {
        result.failure = "all points on one plane or line";
        return result;
    }
    const auto optimal = shape.find_optimal_alpha(1);
    if (optimal == shape.alpha_end()) {
        result.failure = "no alpha gives one solid component";
        return result;
    }
    const double alpha_min = CGAL::to_double(*optimal);
    const double alpha = alpha_min * options.alpha_factor * options.alpha_factor;
    shape.set_alpha(alpha);
    result.alpha_min_radius = std::sqrt(alpha_min);
    result.alpha_radius = std::sqrt(alpha);
    TriangleMesh mesh = regular_facets(shape);
    if (mesh.faces.size() < 4) {
        result.failure = "the alpha shape has no solid part";
        return result;
    }
    if (!make_closed_manifold(mesh) || !check_closed(mesh).closed()) {
        result.failure = "the alpha-shape boundary could not be closed";
        return result;
    }
    remove_unused_vertices(mesh);
    result.mesh = std::move(mesh);
    return result;
}

bool simplify_closed_mesh(TriangleMesh& mesh, const SimplifyOptions& options) {
    if (!(options.tolerance >= 0) || options.max_faces < 4)
        throw Error::usage("lobe simplification: tolerance must be >= 0 and max_faces >= 4");
    if (mesh.faces.size() <= std::max<std::size_t>(options.min_faces, 4)) return false;
    SurfaceMesh sm;
    if (!to_surface_mesh(mesh, sm)) return false;
    // A closed triangle mesh has 3F/2 edges.
    const ToleranceOrCountStop stop{options.tolerance * options.tolerance, options.max_faces * 3 / 2,
                                    std::max<std::size_t>(options.min_faces, 4) * 3 / 2};
    SMS::GarlandHeckbert_plane_policies<SurfaceMesh, K> policies(sm);
    // Bounded normal change rejects collapses that would fold a face over (keeps the surface
    // free of flipped triangles, so the outward orientation survives).
    SMS::Bounded_normal_change_placement<SMS::GarlandHeckbert_plane_policies<SurfaceMesh, K>> placement(policies);
    SMS::edge_collapse(sm, stop, CGAL::parameters::get_cost(policies).get_placement(placement));
    sm.collect_garbage();
    TriangleMesh simplified = from_surface_mesh(sm, mesh.origin);
    if (!check_closed(simplified).closed() || simplified.signed_volume() <= 0) return false;
    mesh = std::move(simplified);
    return true;
}

namespace {

Point to_point(const Eigen::Vector3f& p) { return Point(p.x(), p.y(), p.z()); }

}  // namespace

void inflate_to_contain(TriangleMesh& coarse, const TriangleMesh& fine) {
    std::vector<Triangle> triangles;
    std::vector<int> face_of;  // coarse face of each (non-degenerate) triangle
    for (std::size_t i = 0; i < coarse.faces.size(); ++i) {
        const auto& f = coarse.faces[i];
        const Triangle t(to_point(coarse.vertices[f[0]]), to_point(coarse.vertices[f[1]]), to_point(coarse.vertices[f[2]]));
        if (t.is_degenerate()) continue;
        triangles.push_back(t);
        face_of.push_back(static_cast<int>(i));
    }
    if (triangles.empty()) return;
    const AabbTree tree(triangles.cbegin(), triangles.cend());
    const std::vector<Eigen::Vector3f> normal = coarse.vertex_normals();
    std::vector<float> push(coarse.vertices.size(), 0.0f);
    for (const Eigen::Vector3f& p : fine.vertices) {
        const auto [closest, primitive] = tree.closest_point_and_primitive(to_point(p));
        const auto& f = coarse.faces[face_of[primitive - triangles.cbegin()]];
        const Eigen::Vector3f face_normal =
                (coarse.vertices[f[1]] - coarse.vertices[f[0]]).cross(coarse.vertices[f[2]] - coarse.vertices[f[0]]).normalized();
        const float outside = (p - to_eigen(closest)).dot(face_normal);
        if (!(outside > 0)) continue;
        // Each corner moves along its own normal far enough to carry the face's plane past p
        // (steep corners are capped, so a sharp edge does not shoot out).
        for (int v : f) push[v] = std::max(push[v], outside / std::max(0.5f, normal[v].dot(face_normal)));
    }
    for (std::size_t v = 0; v < coarse.vertices.size(); ++v) coarse.vertices[v] += push[v] * normal[v];
}

struct MeshDistance::Impl {
    std::vector<Triangle> triangles;
    AabbTree tree;
};

MeshDistance::MeshDistance(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()), origin_(mesh.origin) {
    if (mesh.faces.empty()) throw Error::usage("mesh distance: the mesh has no faces");
    impl_->triangles.reserve(mesh.faces.size());
    auto point = [&](int v) {
        const auto& p = mesh.vertices[v];
        return Point(p.x(), p.y(), p.z());
    };
    for (const auto& f : mesh.faces) {
        Triangle t(point(f[0]), point(f[1]), point(f[2]));
        if (!t.is_degenerate()) impl_->triangles.push_back(t);
    }
    if (impl_->triangles.empty()) throw Error::usage("mesh distance: every face of the mesh is degenerate");
    impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
    impl_->tree.build();
    impl_->tree.accelerate_distance_queries();  // before the parallel queries: builds the kd-tree once
}

MeshDistance::~MeshDistance() = default;

double MeshDistance::distance(const Eigen::Vector3d& p) const {
    return std::sqrt(CGAL::to_double(impl_->tree.squared_distance(Point(p.x(), p.y(), p.z()))));
}

std::vector<float> MeshDistance::distances(const PointCloud& cloud) const {
    std::vector<float> out(cloud.size());
    const Eigen::Vector3d shift = cloud.origin - origin_;
    treelobes::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 1024), [&](const auto& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i)
            out[i] = static_cast<float>(distance(cloud.positions[i].cast<double>() + shift));
    });
    return out;
}

}  // namespace treelobes
