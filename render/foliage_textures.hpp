// Foliage impostor textures of Lluch et al. 2010 (via Ong's seminar report, §3.2): the foliage inside a box,
// projected orthographically on each of the box's six diagonal planes and rendered offscreen with
// the project's rasteriser into size x size RGBA images (transparent where there is no leaf).
//
// A diagonal plane of a box contains two opposite parallel edges: for each axis a, the two
// diagonals of the face perpendicular to a, swept along a. Plane k is the rectangle
// corner + s*u + t*v (s, t in [0, 1]); the texture maps s to the image column and t to the row
// (t = 1 at the top), so a renderer puts texel (x, y) at s = (x + 0.5)/size, t = 1 - (y + 0.5)/size.
// The texture is stretched to the rectangle: the full resolution is used whatever the aspect ratio.
// Every point of the box projects inside the rectangle, so no foliage is cut off. v is chosen as
// the side with the larger z component, so trees stand upright on the planes that contain z.
#pragma once

#include "core/triangle_mesh.hpp"
#include "render/image.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <span>
#include <string>
#include <vector>

namespace treelobes::render {

struct DiagonalPlane {
    std::string name;  // "z1" "z2" (contain the z axis), "y1" "y2", "x1" "x2"
    Eigen::Vector3d corner{0, 0, 0};
    Eigen::Vector3d u{1, 0, 0};                                         // image columns
    Eigen::Vector3d v{0, 0, 1};                                         // image rows, bottom to top
    Eigen::Vector3d normal() const { return u.cross(v).normalized(); }  // the viewer's side
};

// The six diagonal planes of the box [lo, hi] in the order z1 z2 y1 y2 x1 x2; throws Error::usage for an empty or flat box.
std::array<DiagonalPlane, 6> diagonal_planes(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);

// Foliage to draw: meshes (local coordinates + origin) with one base colour each; the rasteriser
// shades them by orientation.
struct FoliageLayer {
    const TriangleMesh* mesh = nullptr;
    Rgba colour{60, 130, 45, 255};
};

// Six textures, one per diagonal plane of [lo, hi] (world coordinates), in diagonal_planes order.
// Each is rendered at size * supersample pixels and box-filtered down (alpha = coverage, colour
// averaged over the covered samples), so leaves smaller than a texel still show as soft foliage
// instead of dropping out or aliasing into speckle.
std::array<Image, 6> render_diagonal_textures(std::span<const FoliageLayer> layers, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                              int size = 128, int supersample = 4);

// Box-filters an image down by an integer factor (width and height must be multiples of it):
// alpha is the mean alpha, colour the alpha-weighted mean colour.
Image downsample(const Image& image, int factor);

// Tiles images of equal size into one atlas, `columns` per row, row-major, transparent padding.
// Tile i sits at pixel (tile_x(i), tile_y(i)) = ((i % columns) * w, (i / columns) * h).
Image pack_atlas(std::span<const Image> tiles, int columns);

}  // namespace treelobes::render
