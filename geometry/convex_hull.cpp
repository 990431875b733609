#include "geometry/convex_hull.hpp"

#include "geometry/union_find.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <boost/geometry.hpp>
#include <boost/geometry/geometries/multi_point.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <map>

namespace treelobes {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Face = std::array<int, 3>;

struct RawHull {
    std::vector<Point> corners;
    std::vector<Face> faces;  // outward, counter-clockwise
};

RawHull cgal_hull(const std::vector<Eigen::Vector3f>& points) {
    std::vector<Point> input;
    input.reserve(points.size());
    for (const auto& p : points) input.emplace_back(p.x(), p.y(), p.z());
    CGAL::Surface_mesh<Point> mesh;
    CGAL::convex_hull_3(input.begin(), input.end(), mesh);
    RawHull hull;
    std::vector<int> index(mesh.number_of_vertices(), -1);
    for (auto v : mesh.vertices()) {
        index[v.idx()] = static_cast<int>(hull.corners.size());
        hull.corners.push_back(mesh.point(v));
    }
    for (auto f : mesh.faces()) {
        Face face{};
        int k = 0;
        for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
            if (k < 3) face[k++] = index[v.idx()];
        if (k == 3) hull.faces.push_back(face);
    }
    return hull;
}

// Faces joined when they share an edge and lie in one plane (exact predicate).
std::vector<int> planar_facet_of_face(const RawHull& hull) {
    std::map<std::pair<int, int>, int> face_of_edge;
    for (std::size_t f = 0; f < hull.faces.size(); ++f)
        for (int k = 0; k < 3; ++k) face_of_edge[{hull.faces[f][k], hull.faces[f][(k + 1) % 3]}] = static_cast<int>(f);
    UnionFind facets(hull.faces.size());
    for (std::size_t f = 0; f < hull.faces.size(); ++f) {
        const Face& a = hull.faces[f];
        for (int k = 0; k < 3; ++k) {
            const auto other = face_of_edge.find({a[(k + 1) % 3], a[k]});
            if (other == face_of_edge.end()) continue;
            const Face& b = hull.faces[other->second];
            const int apex = b[0] != a[k] && b[0] != a[(k + 1) % 3] ? b[0] : b[1] != a[k] && b[1] != a[(k + 1) % 3] ? b[1] : b[2];
            const auto& c = hull.corners;
            if (CGAL::orientation(c[a[0]], c[a[1]], c[a[2]], c[apex]) == CGAL::COPLANAR) facets.unite(static_cast<int>(f), other->second);
        }
    }
    std::vector<int> facet(hull.faces.size());
    for (std::size_t f = 0; f < hull.faces.size(); ++f) facet[f] = facets.find(static_cast<int>(f));
    return facet;
}

// The boundary of one planar facet as a counter-clockwise cycle of its strictly convex corners.
std::vector<int> facet_polygon(const RawHull& hull, const std::vector<int>& faces) {
    std::map<std::pair<int, int>, int> directed;
    for (int f : faces)
        for (int k = 0; k < 3; ++k) ++directed[{hull.faces[f][k], hull.faces[f][(k + 1) % 3]}];
    std::map<int, int> next;
    for (const auto& [edge, count] : directed)
        if (!directed.count({edge.second, edge.first})) next[edge.first] = edge.second;
    std::vector<int> cycle{next.begin()->first};
    for (int v = next.at(cycle.front()); v != cycle.front() && cycle.size() <= next.size(); v = next.at(v)) cycle.push_back(v);
    std::vector<int> corners;
    const auto& c = hull.corners;
    for (std::size_t k = 0; k < cycle.size(); ++k) {
        const int before = cycle[(k + cycle.size() - 1) % cycle.size()], after = cycle[(k + 1) % cycle.size()];
        if (!CGAL::collinear(c[before], c[cycle[k]], c[after])) corners.push_back(cycle[k]);
    }
    return corners;
}

bool lexicographically_less(const Point& a, const Point& b) { return CGAL::compare_xyz(a, b) == CGAL::SMALLER; }

TriangleMesh canonical_mesh(const RawHull& hull, const Eigen::Vector3d& origin) {
    const std::vector<int> facet = planar_facet_of_face(hull);
    std::map<int, std::vector<int>> faces_of_facet;
    for (std::size_t f = 0; f < facet.size(); ++f) faces_of_facet[facet[f]].push_back(static_cast<int>(f));
    std::vector<Face> fans;
    for (const auto& [root, faces] : faces_of_facet) {
        std::vector<int> polygon = facet_polygon(hull, faces);
        const auto first = std::min_element(polygon.begin(), polygon.end(),
                                            [&](int a, int b) { return lexicographically_less(hull.corners[a], hull.corners[b]); });
        std::rotate(polygon.begin(), first, polygon.end());
        for (std::size_t k = 1; k + 1 < polygon.size(); ++k) fans.push_back({polygon[0], polygon[k], polygon[k + 1]});
    }
    std::vector<int> order;
    std::vector<bool> used(hull.corners.size(), false);
    for (const Face& f : fans)
        for (int v : f) used[v] = true;
    for (std::size_t v = 0; v < used.size(); ++v)
        if (used[v]) order.push_back(static_cast<int>(v));
    std::sort(order.begin(), order.end(), [&](int a, int b) { return lexicographically_less(hull.corners[a], hull.corners[b]); });
    std::vector<int> rank(hull.corners.size(), -1);
    TriangleMesh mesh;
    mesh.origin = origin;
    for (int v : order) {
        rank[v] = static_cast<int>(mesh.vertices.size());
        const Point& p = hull.corners[v];
        mesh.vertices.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    }
    for (const Face& f : fans) {
        Face renamed{rank[f[0]], rank[f[1]], rank[f[2]]};
        std::rotate(renamed.begin(), std::min_element(renamed.begin(), renamed.end()), renamed.end());
        mesh.faces.push_back(renamed);
    }
    std::sort(mesh.faces.begin(), mesh.faces.end());
    return mesh;
}

}  // namespace

TriangleMesh convex_hull(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3d& origin) {
    if (points.size() < 4) return TriangleMesh{origin, {}, {}};
    const RawHull hull = cgal_hull(points);
    if (hull.faces.size() < 4) return TriangleMesh{origin, {}, {}};
    TriangleMesh mesh = canonical_mesh(hull, origin);
    if (mesh.faces.size() < 4 || !(mesh.signed_volume() > 1e-12)) return TriangleMesh{origin, {}, {}};  // flat or collinear input
    return mesh;
}

std::vector<Eigen::Vector2d> projected_hull(std::span<const Eigen::Vector3f> points) {
    namespace bg = boost::geometry;
    using Point = bg::model::d2::point_xy<double>;
    if (points.size() < 3) return {};
    bg::model::multi_point<Point> cloud;
    cloud.reserve(points.size());
    for (const auto& p : points) cloud.emplace_back(p.x(), p.y());
    bg::model::polygon<Point> hull;  // clockwise and closed: the first corner repeated last
    bg::convex_hull(cloud, hull);
    const auto& corners = hull.outer();
    std::vector<Eigen::Vector2d> ring;
    for (auto corner = corners.rbegin() + 1; corner < corners.rend(); ++corner) ring.emplace_back(corner->x(), corner->y());
    if (ring_area(ring) <= 0.0) return {};
    return ring;
}

double ring_area(std::span<const Eigen::Vector2d> ring) {
    if (ring.size() < 3) return 0.0;
    double twice = 0.0;  // the shoelace formula
    for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) twice += ring[j].x() * ring[i].y() - ring[i].x() * ring[j].y();
    return std::abs(twice) / 2.0;
}

double equal_area_diameter(double area) { return area > 0 ? 2.0 * std::sqrt(area / std::numbers::pi) : 0.0; }

}  // namespace treelobes
