#include "render/foliage_textures.hpp"

#include "core/error.hpp"
#include "render/rasterizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace treelobes::render {

std::array<DiagonalPlane, 6> diagonal_planes(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    const Eigen::Vector3d size = hi - lo;
    if (!lo.allFinite() || !hi.allFinite() || (size.array() <= 0).any())
        throw Error::usage("foliage textures: the box must have a positive extent along every axis");
    std::array<DiagonalPlane, 6> planes;
    const char* names[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const Eigen::Vector3d axis = size[a] * Eigen::Vector3d::Unit(a);
        const Eigen::Vector3d eb = size[b] * Eigen::Vector3d::Unit(b), ec = size[c] * Eigen::Vector3d::Unit(c);
        // Diagonal 1 runs from (lo_b, lo_c) to (hi_b, hi_c); diagonal 2 from (hi_b, lo_c) to (lo_b, hi_c).
        const Eigen::Vector3d corners[2] = {lo, lo + eb};
        const Eigen::Vector3d diagonals[2] = {eb + ec, ec - eb};
        for (int k = 0; k < 2; ++k) {
            DiagonalPlane& p = planes[static_cast<std::size_t>(2 * (2 - a) + k)];  // z planes first
            p.name = std::string(names[a]) + std::to_string(k + 1);
            p.corner = corners[k];
            // The side with the larger upward component becomes the image's vertical.
            const bool axis_up = std::abs(axis.normalized().z()) >= std::abs(diagonals[k].normalized().z());
            p.u = axis_up ? diagonals[k] : axis;
            p.v = axis_up ? axis : diagonals[k];
            if (p.v.z() < 0) {  // keep "up" pointing up: start the rectangle at the other end of v
                p.corner += p.v;
                p.v = -p.v;
            }
        }
    }
    return planes;
}

namespace {

// The mesh in plane coordinates (s, t, w): s and t in [0, 1] across the rectangle, w the height
// above the plane in units of |u| (the rasteriser only uses w for depth and shading).
TriangleMesh to_plane_coordinates(const TriangleMesh& mesh, const DiagonalPlane& plane) {
    const Eigen::Vector3d n = plane.normal();
    const double uu = plane.u.squaredNorm(), vv = plane.v.squaredNorm(), un = plane.u.norm();
    TriangleMesh out;
    out.faces = mesh.faces;
    out.vertices.reserve(mesh.vertices.size());
    for (const Eigen::Vector3f& local : mesh.vertices) {
        const Eigen::Vector3d d = mesh.origin + local.cast<double>() - plane.corner;
        out.vertices.emplace_back(static_cast<float>(d.dot(plane.u) / uu), static_cast<float>(d.dot(plane.v) / vv),
                                  static_cast<float>(d.dot(n) / un));
    }
    return out;
}

}  // namespace

Image downsample(const Image& image, int factor) {
    if (factor < 1 || image.width % factor != 0 || image.height % factor != 0)
        throw Error::usage("downsample: the image size must be a multiple of the factor");
    if (factor == 1) return image;
    Image out(image.width / factor, image.height / factor, Rgba{0, 0, 0, 0});
    const double samples = static_cast<double>(factor) * factor;
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x) {
            double rgb[3] = {0, 0, 0}, alpha = 0;
            for (int dy = 0; dy < factor; ++dy)
                for (int dx = 0; dx < factor; ++dx) {
                    const Rgba p = image.at(x * factor + dx, y * factor + dy);
                    for (int c = 0; c < 3; ++c) rgb[c] += static_cast<double>(p[c]) * p[3];
                    alpha += p[3];
                }
            if (alpha == 0) continue;
            Rgba q;
            for (int c = 0; c < 3; ++c) q[static_cast<std::size_t>(c)] = static_cast<std::uint8_t>(std::lround(rgb[c] / alpha));
            q[3] = static_cast<std::uint8_t>(std::lround(alpha / samples));
            out.set(x, y, q);
        }
    return out;
}

std::array<Image, 6> render_diagonal_textures(std::span<const FoliageLayer> layers, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                              int size, int supersample) {
    if (size < 1 || size > 8192) throw Error::usage("foliage textures: the texture size must be 1..8192 pixels");
    if (supersample < 1 || supersample > 16) throw Error::usage("foliage textures: supersampling must be 1..16");
    const auto planes = diagonal_planes(lo, hi);
    std::array<Image, 6> textures;
    for (std::size_t k = 0; k < planes.size(); ++k) {
        std::vector<TriangleMesh> projected;
        projected.reserve(layers.size());
        double w_lo = std::numeric_limits<double>::max(), w_hi = -w_lo;
        for (const FoliageLayer& layer : layers) {
            projected.push_back(to_plane_coordinates(*layer.mesh, planes[k]));
            for (const Eigen::Vector3f& p : projected.back().vertices) {
                w_lo = std::min(w_lo, static_cast<double>(p.z()));
                w_hi = std::max(w_hi, static_cast<double>(p.z()));
            }
        }
        if (w_lo > w_hi) w_lo = w_hi = 0.0;
        // Looking down -w at the unit square: image right = +s, image up = +t, one texel per 1/size.
        View view;
        view.forward = Eigen::Vector3d(0, 0, -1);
        view.up = Eigen::Vector3d(0, 1, 0);
        view.lo = Eigen::Vector3d(0, 0, w_lo);
        view.hi = Eigen::Vector3d(1, 1, w_hi);
        view.margin = 0.0;
        Rasterizer rasterizer(size * supersample, size * supersample, view, Rgba{0, 0, 0, 0});
        for (std::size_t l = 0; l < layers.size(); ++l) rasterizer.draw_mesh(projected[l], layers[l].colour);
        textures[k] = downsample(rasterizer.image(), supersample);
    }
    return textures;
}

Image pack_atlas(std::span<const Image> tiles, int columns) {
    if (tiles.empty()) return Image();
    if (columns < 1) throw Error::usage("atlas: at least one column");
    const int w = tiles.front().width, h = tiles.front().height;
    for (const Image& t : tiles)
        if (t.width != w || t.height != h) throw Error::usage("atlas: all tiles must have the same size");
    const int count = static_cast<int>(tiles.size());
    const int cols = std::min(columns, count);
    const int rows = (count + cols - 1) / cols;
    Image atlas(cols * w, rows * h, Rgba{0, 0, 0, 0});
    for (int i = 0; i < count; ++i) {
        const Image& t = tiles[static_cast<std::size_t>(i)];
        const int x0 = (i % cols) * w, y0 = (i / cols) * h;
        for (int y = 0; y < h; ++y)
            std::copy_n(t.pixels.begin() + static_cast<std::ptrdiff_t>(y) * w * 4, static_cast<std::size_t>(w) * 4,
                        atlas.pixels.begin() + (static_cast<std::ptrdiff_t>(y0 + y) * atlas.width + x0) * 4);
    }
    return atlas;
}

}  // namespace treelobes::render
