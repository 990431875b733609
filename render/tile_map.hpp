// The top view of a segmented tile: every point seen from above, coloured by its tree (ground
// and points of no tree in grey, "trees" that look like buildings in grey stripes), shaded by
// height, with each tree's stem position marked and its id written beside it. The map is what
// people look at first after `treelobes tile`.
#pragma once

#include "core/point_cloud.hpp"
#include "render/image.hpp"

#include <Eigen/Core>

#include <optional>
#include <span>
#include <vector>

namespace treelobes::render {

struct TileMapStem {
    int id = 0;
    Eigen::Vector3d position{0, 0, 0};  // local frame of the cloud
    bool not_a_tree = false;            // a "tree" that looks like a building: grey stripes and a ring, not a tree's colour and a dot
};

struct TileMapOptions {
    int max_side_px = 1600;     // the longer side of the tile fills this many pixels...
    double min_pixel_m = 0.05;  // ...unless a pixel would be smaller than this (metres)
    int margin_px = 12;
    bool labels = true;  // tree ids beside the stem marks
};

// Colour of tree `id` (> 0): a fixed hue sequence, so neighbouring ids differ.
Rgba tree_colour(int id);

// A label's box on the image: top-left corner and size in pixels.
struct LabelBox {
    int x = 0, y = 0, width = 0, height = 0;
};

// Where each mark's label goes, in the marks' order (the first are placed first): to the right of
// its mark, else left, above or below it, wherever the box stays on the image and overlaps no
// mark (discs of `mark_radius`) and no box placed before it; nullopt where none of the four is
// free. Thousands of trees on one tile then show the ids that fit instead of a carpet of
// overwritten digits. `sizes` holds one label size (width, height) per mark.
std::vector<std::optional<LabelBox>> place_labels(int width, int height, std::span<const Eigen::Vector2i> marks, int mark_radius,
                                                  std::span<const Eigen::Vector2i> sizes);

// `tree_id` has one entry per point (0 = no tree); `height_above_ground` one per point (empty:
// shaded by z). Throws Error(Internal) for mismatched sizes or an empty cloud.
Image draw_tile_map(const PointCloud& cloud, std::span<const int> tree_id, std::span<const float> height_above_ground,
                    std::span<const TileMapStem> stems, const TileMapOptions& options = {});

}  // namespace treelobes::render
