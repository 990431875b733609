// A tile with a buffer: the tile's own points plus its neighbours' points within a margin, so
// that a tree crossing the tile's edge is segmented and modelled whole. The tile owns the trees
// whose stem base lies in its core (its own area); the others are its neighbours' (docs/survey.md).
#pragma once

#include "core/cloud_io.hpp"
#include "core/point_cloud.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace treelobes::survey {

// The area whose trees a tile owns, in original (CRS) coordinates.
struct TileCore {
    double min_x = 0, min_y = 0, max_x = 0, max_y = 0;
    // A retile square is half-open, [min, max), so that a point on an edge shared by two squares
    // belongs to exactly one; the bounds of a tile's points are closed, [min, max].
    bool half_open = false;
    std::string source;  // "retile name", "header bounds" or "point bounds"
    bool holds(double x, double y) const;
};

// The square [x, x + size) x [y, y + size) of a tile named `<prefix>_<x>_<y>` by `retile` (its
// lower-left corner in the name). Throws Error(Usage) when the file name does not end in two
// numbers separated by underscores.
TileCore core_from_retile_name(const std::filesystem::path& tile, double size);
// The closed bounding box a LAS/LAZ header states (x, y); nullopt for formats without one.
std::optional<TileCore> core_from_header(const std::filesystem::path& tile);
// The closed bounding box of the points, for formats without header bounds. Throws on an empty cloud.
TileCore core_from_points(const PointCloud& cloud);

struct BufferedTile {
    PointCloud cloud;                                    // the tile's own points first, then the buffer's
    std::size_t own_points = 0;                          // the first own_points points are the tile's
    std::vector<std::filesystem::path> neighbours_read;  // files that gave buffer points, sorted
    std::size_t neighbours_skipped = 0;                  // files whose header bounds miss the buffer
};

// Appends to `tile` (the points of `input`) the points of the files in `candidates` (the input
// itself is left out) that lie within `buffer` metres of the core (the box around it, in x and
// y) but outside the core. A LAS/LAZ file whose header bounds miss that box is not read; COPC
// files read only the octree nodes that meet it; other formats are read whole and filtered.
// Throws Error(InvalidInput) when a neighbour's CRS or attributes differ from the tile's.
BufferedTile add_buffer(PointCloud tile, const std::filesystem::path& input, const TileCore& core, double buffer,
                        const std::vector<std::filesystem::path>& candidates);

// Points the buffer will add, from the headers only (for the memory estimate): for each
// candidate but the input whose header bounds meet the buffered box, its point count times the
// share of its bounds' area inside the box; the whole count for a file without header bounds,
// and for every candidate when the core is not known before reading (an input without header bounds).
std::size_t estimate_buffer_points(const std::filesystem::path& input, const std::optional<TileCore>& core, double buffer,
                                   const std::vector<std::filesystem::path>& candidates);

// The box of original coordinates a buffered tile covers: the core grown by `buffer` in x and y,
// z unbounded.
Box3d buffered_box(const TileCore& core, double buffer);

}  // namespace treelobes::survey
