#include "export/convex_hull.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

namespace treelobes::exporting {

TriangleMesh convex_hull(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3d& origin) {
    using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
    using Point = Kernel::Point_3;
    TriangleMesh hull;
    hull.origin = origin;
    if (points.size() < 4) return hull;
    std::vector<Point> input;
    input.reserve(points.size());
    for (const auto& p : points) input.emplace_back(p.x(), p.y(), p.z());
    CGAL::Surface_mesh<Point> mesh;
    CGAL::convex_hull_3(input.begin(), input.end(), mesh);
    std::vector<int> index(mesh.number_of_vertices(), -1);
    for (auto v : mesh.vertices()) {
        index[v.idx()] = static_cast<int>(hull.vertices.size());
        const Point& p = mesh.point(v);
        hull.vertices.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    }
    for (auto f : mesh.faces()) {
        std::array<int, 3> face{};
        int k = 0;
        for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
            if (k < 3) face[k++] = index[v.idx()];
        if (k == 3) hull.faces.push_back(face);
    }
    if (hull.faces.size() < 4 || !(hull.signed_volume() > 1e-12)) return TriangleMesh{origin, {}, {}};  // flat or collinear input
    return hull;
}

}  // namespace treelobes::exporting
