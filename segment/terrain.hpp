// Terrain of a LiDAR tile: which points are ground, a digital terrain model (DTM) on a regular
// grid and every point's height above that ground.
//
// Three cases, detected in this order:
//  - "normalised": the tile was height-normalised already (lidR's normalize_height: ground near
//    z = 0 in the file's coordinates, and flat). The DTM is flat at global z = 0 and the height above
//    ground is the point's global z.
//  - "classified": the tile carries ASPRS class 2 (ground). Those points are the ground as given.
//  - "filtered": neither; ground is found by the progressive morphological filter (Zhang et al.
//    2003, §2) run on the lowest point of each DTM cell, then every point within
//    `ground_tolerance` of the resulting surface counts as ground.
// The DTM is the mean height of the ground points of each cell; cells without ground are filled
// from the 12 nearest ground cells by a plane fitted with inverse-squared-distance weights (no
// holes inside the tile; slopes stay slopes across holes under crowns).
#pragma once

#include "core/point_cloud.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace treelobes {

struct TerrainOptions {
    float cell_size = 1.0f;  // DTM cell edge (metres)
    // Progressive morphological filter (Zhang et al. 2003, §2.2), used only for "filtered":
    float max_window_size = 20.0f;   // largest opening window (metres): wider than the widest crown or building
    float terrain_slope = 0.7f;      // steepest expected terrain (rise over run; 0.7 ~ 35 degrees)
    float initial_distance = 0.3f;   // height tolerance of the smallest window (metres)
    float max_distance = 3.0f;       // height tolerance cap of the largest windows (metres)
    float ground_tolerance = 0.25f;  // points this close above (or below) the DTM surface are ground (metres)
    // Detection of an already normalised tile: the lowest points of at least half of the
    // occupied 5 m cells must lie within this distance of global z = 0 (metres), without a slope.
    float normalised_tolerance = 0.5f;
    bool use_classification = true;  // false: ignore an input class 2 and filter afresh
};

// Regular grid of terrain heights in the cloud's local frame.
struct DtmGrid {
    Eigen::Vector2d origin{0, 0};  // local xy of the outer corner of cell (0, 0)
    float cell_size = 1.0f;
    int columns = 0;
    int rows = 0;
    std::vector<float> heights;  // rows x columns, row-major (row = y index), local z; NaN = no data

    bool empty() const { return heights.empty(); }
    float at(int column, int row) const { return heights[static_cast<std::size_t>(row) * columns + column]; }
    // Terrain height (local z) at local (x, y): bilinear between cell centres, clamped to the
    // grid's edge outside it. NaN for an empty grid or where the surrounding cells hold no data.
    float height_at(float x, float y) const;
};

struct Terrain {
    DtmGrid dtm;
    std::vector<float> height_above_ground;  // per point: z - DTM(x, y) (metres)
    std::vector<std::uint8_t> is_ground;     // per point: 1 = ground
    std::string ground_source;               // "classified", "normalised" or "filtered"
    std::size_t ground_points = 0;           // points with is_ground = 1
};

// The edge of a grid over the cloud's xy extent: `cell`, or coarser where that grid would hold
// more than 4 cells per point. A grid finer than its points can fill only costs memory: laspy's
// simple.laz (1,065 points spread over 3.4 x 4.6 km) took 15.6M DTM cells, 1.8 GB and 19 s.
float grid_cell_for_points(const PointCloud& cloud, float cell);

// Ground, DTM and heights for a tile (the DTM's cell from grid_cell_for_points). An empty cloud gives an empty Terrain (empty grid, no
// points, ground_source "none"). Throws Error(Usage) for non-positive options and
// Error(InvalidInput) for non-finite coordinates.
Terrain analyse_terrain(const PointCloud& cloud, const TerrainOptions& options);

// ESRI ASCII grid (.asc) of the DTM in global coordinates (`origin` = the cloud's origin);
// NODATA_value -9999. Written atomically. Throws Error(InvalidInput) for an empty grid.
void write_ascii_grid(const DtmGrid& dtm, const Eigen::Vector3d& origin, const std::filesystem::path& path);

// Grey hillshade of the DTM (sun from the north-west, 45 degrees up), one pixel per cell,
// north up, as an 8-bit PNG. Written atomically. Throws Error(InvalidInput) for an empty grid.
void write_hillshade_png(const DtmGrid& dtm, const std::filesystem::path& path);

}  // namespace treelobes
