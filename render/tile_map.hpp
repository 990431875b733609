// The top view of a segmented tile: every point seen from above, coloured by its tree (ground
// and points of no tree in grey), shaded by height, with each tree's stem position marked and
// its id written beside it. The map is what people look at first after `treelobes tile`.
#pragma once

#include "core/point_cloud.hpp"
#include "render/image.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace treelobes::render {

struct TileMapStem {
    int id = 0;
    Eigen::Vector3d position{0, 0, 0};  // local frame of the cloud
};

struct TileMapOptions {
    int max_side_px = 1600;     // the longer side of the tile fills this many pixels...
    double min_pixel_m = 0.05;  // ...unless a pixel would be smaller than this (metres)
    int margin_px = 12;
    bool labels = true;  // tree ids beside the stem marks
};

// Colour of tree `id` (> 0): a fixed hue sequence, so neighbouring ids differ.
Rgba tree_colour(int id);

// `tree_id` has one entry per point (0 = no tree); `height_above_ground` one per point (empty:
// shaded by z). Throws Error(Internal) for mismatched sizes or an empty cloud.
Image draw_tile_map(const PointCloud& cloud, std::span<const int> tree_id, std::span<const float> height_above_ground,
                    std::span<const TileMapStem> stems, const TileMapOptions& options = {});

}  // namespace treelobes::render
