// A small orthographic z-buffer rasteriser: triangle meshes with Lambert shading, points and
// line segments. Enough for previews of trees and scans, lobe textures and foliage impostors,
// without an OpenGL context (CI machines have no display).
#pragma once

#include "core/point_cloud.hpp"
#include "core/tree_graph.hpp"
#include "core/triangle_mesh.hpp"
#include "render/image.hpp"

#include <Eigen/Core>

#include <vector>

namespace treelobes::render {

// Orthographic view: looks along `forward` with `up` roughly vertical in the image, framing
// the axis-aligned box [lo, hi] (world coordinates) with a margin.
struct View {
    Eigen::Vector3d forward{0, 1, 0};
    Eigen::Vector3d up{0, 0, 1};
    Eigen::Vector3d lo{-1, -1, -1}, hi{1, 1, 1};
    double margin = 0.05;  // fraction of the frame left empty on each side
    // When > 0: the half extents (metres) framed on the image axes, around the box's centre,
    // instead of the box's own; keeps one scale over the frames of an orbit.
    double half_width = 0, half_height = 0;

    // A view from the side at `azimuth_deg` around the vertical axis (0 = looking along +y)
    // and `elevation_deg` above the horizon.
    static View side(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double azimuth_deg = 0, double elevation_deg = 10);

    // Width over height of the box [lo, hi] as this view sees it: the image shape in which the
    // box fills the frame.
    double aspect() const;
};

class Rasterizer {
public:
    Rasterizer(int width, int height, const View& view, Rgba background = {255, 255, 255, 255});

    // World positions are `origin + local`; meshes and clouds carry their own origin.
    void draw_mesh(const TriangleMesh& mesh, Rgba colour);
    void draw_points(const PointCloud& cloud, Rgba colour, int size_px = 1);
    void draw_points(const std::vector<Eigen::Vector3d>& points, const std::vector<Rgba>& colours, int size_px = 1);
    void draw_skeleton(const TreeGraph& tree, Rgba colour);
    void draw_segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Rgba colour);

    const Image& image() const { return image_; }
    // Number of pixels written at least once (coverage checks in tests).
    std::size_t covered_pixels() const;
    // Per pixel (row-major), whether anything was drawn there: the silhouette of what was drawn.
    std::vector<bool> coverage() const;

private:
    Eigen::Vector3d project(const Eigen::Vector3d& world) const;  // pixel x, pixel y, depth
    void plot(int x, int y, double depth, Rgba colour);
    void fill_triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, Rgba colour);

    Image image_;
    std::vector<double> depth_;
    Eigen::Vector3d right_, up_, forward_, centre_;
    double scale_ = 1.0;  // pixels per metre
};

// Intersection over union of two silhouettes of the same size (1 when both are empty); compares
// the outlines of two models drawn with the same view (`treelobes rebuild`).
double silhouette_iou(const std::vector<bool>& a, const std::vector<bool>& b);

// The crown's outline as one would draw it around a silhouette (width x height, row-major): a
// morphological closing with a disc of `closing_px` pixels (gaps between leaves and twigs
// narrower than the disc are bridged), then every hole not open to the image border filled.
// Two crowns of the same shape but other leaf and twig placement have nearly the same outline,
// where their raw silhouettes share few pixels (docs/rebuild.md).
std::vector<bool> crown_outline(const std::vector<bool>& mask, int width, int height, int closing_px);

// Multiplies an RGB colour by a light factor in [0, 1] (alpha unchanged).
Rgba shade(Rgba colour, double light);

}  // namespace treelobes::render
