// Hull features: convex hull and alpha-shape volumes from one CGAL Delaunay tetrahedrisation of
// the voxel points (thinned to a coarser grid to bound the cost). A tetrahedron belongs to the
// alpha complex of squared radius alpha when its circumsphere's squared radius is at most alpha
// (the interior cells of CGAL::Alpha_shape_3 at that alpha); all finite cells make the convex hull.
#include "classify/feature_groups.hpp"
#include "geometry/grid_thinning.hpp"

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cmath>
#include <numbers>

namespace treelobes::classify::detail {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel>;
using Point = Kernel::Point_3;

constexpr int kAlphaDivisors[] = {10, 20, 40};  // alpha radius = H / divisor

// One point per cell of size `cell` (the first one met), as CGAL points.
std::vector<Point> thin_to_grid(const std::vector<Eigen::Vector3f>& pts, float cell) {
    std::vector<Point> out;
    for (const std::size_t i : first_point_per_cell(pts, cell)) out.emplace_back(pts[i].x(), pts[i].y(), pts[i].z());
    return out;
}

}  // namespace

void describe_hull(Catalogue& c) {
    c.add("hull_box_ratio", "1", "convex hull volume / (H x crown_width_major x crown_width_minor)");
    c.add("hull_cylinder_ratio", "1", "convex hull volume / (pi R^2 H)");
    c.add("hull_sphericity", "1", "pi^(1/3) (6 V)^(2/3) / A of the convex hull (1 for a sphere)");
    c.add("hull_centroid_height", "1", "height of the convex hull's volume centroid / H");
    for (int d : kAlphaDivisors)
        c.add("alpha_hull_ratio_" + std::to_string(d), "1",
              "alpha-shape volume / convex hull volume, alpha radius H/" + std::to_string(d) + " (Delaunay cells with circumradius <= H/" +
                      std::to_string(d) + ")");
}

void compute_hull(const TreeFrame& f, FeatureSink& out) {
    const std::vector<Point> pts = thin_to_grid(f.points, std::max(f.voxel, f.height / 60));
    Delaunay dt(pts.begin(), pts.end());
    double volume = 0, centroid_z = 0, area = 0;
    double alpha_volume[std::size(kAlphaDivisors)] = {};
    if (dt.dimension() == 3) {
        for (auto cell = dt.finite_cells_begin(); cell != dt.finite_cells_end(); ++cell) {
            const auto& a = cell->vertex(0)->point();
            const auto& b = cell->vertex(1)->point();
            const auto& c = cell->vertex(2)->point();
            const auto& d = cell->vertex(3)->point();
            const double v = std::abs(CGAL::volume(a, b, c, d));
            volume += v;
            centroid_z += v * (a.z() + b.z() + c.z() + d.z()) / 4;
            const double r2 = CGAL::squared_radius(a, b, c, d);
            for (std::size_t k = 0; k < std::size(kAlphaDivisors); ++k) {
                const double radius = f.height / kAlphaDivisors[k];
                if (r2 <= radius * radius) alpha_volume[k] += v;
            }
        }
        // Every infinite cell has exactly one finite facet, which is a hull facet.
        for (auto cell = dt.all_cells_begin(); cell != dt.all_cells_end(); ++cell) {
            if (!dt.is_infinite(cell)) continue;
            const int inf = cell->index(dt.infinite_vertex());
            const auto& a = cell->vertex((inf + 1) % 4)->point();
            const auto& b = cell->vertex((inf + 2) % 4)->point();
            const auto& c = cell->vertex((inf + 3) % 4)->point();
            area += std::sqrt(CGAL::squared_area(a, b, c));
        }
    }
    std::vector<float> x, y;
    for (const auto& p : f.points) x.push_back(p.x()), y.push_back(p.y());
    const double box = double(f.height) * (quantile(x, 0.98) - quantile(x, 0.02)) * (quantile(y, 0.98) - quantile(y, 0.02));
    const double h = f.height, r = f.crown_radius;
    out.add("hull_box_ratio", box > 0 ? volume / box : 0.0);
    out.add("hull_cylinder_ratio", volume / (std::numbers::pi * r * r * h));
    out.add("hull_sphericity", area > 0 ? std::cbrt(std::numbers::pi) * std::pow(6 * volume, 2.0 / 3.0) / area : 0.0);
    out.add("hull_centroid_height", volume > 0 ? centroid_z / volume / h : 0.0);
    for (std::size_t k = 0; k < std::size(kAlphaDivisors); ++k)
        out.add("alpha_hull_ratio_" + std::to_string(kAlphaDivisors[k]), volume > 0 ? alpha_volume[k] / volume : 0.0);
}

}  // namespace treelobes::classify::detail
