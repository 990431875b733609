// Coarse occupancy of a lobe: which cells of a cubic grid held points of the lobe's cluster.
// A lobe's hull (alpha = 5 alpha_min) is mostly empty space; the occupancy, stored in the .tlobe
// (docs/tlobe.md), lets texturing (lobes/texturing.hpp) put patches where the scan saw the
// crown instead of spreading them uniformly over the hull.
//
// Cells are indexed floor(p / cell) in the tree's local frame, so a grid is given by its first
// cell, its size in cells and one bit per cell (x slowest, z fastest).
#pragma once

#include "core/triangle_mesh.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace treelobes::lobes {

class ByteWriter;
class ByteReader;

struct Occupancy {
    float cell = 0;                              // metres; 0 = no occupancy recorded
    std::array<std::int64_t, 3> first{0, 0, 0};  // index of the grid's first cell
    std::array<std::int64_t, 3> size{0, 0, 0};   // cells along x, y, z
    std::vector<std::uint8_t> bits;              // 1 = the cell held a point; size[0]*size[1]*size[2] entries

    bool empty() const { return cell <= 0 || bits.empty(); }
    bool occupied(const Eigen::Vector3f& p) const;
    std::size_t occupied_count() const;
    Eigen::Vector3f cell_centre(std::size_t index) const;
    bool operator==(const Occupancy&) const = default;
};

inline constexpr std::size_t kMaxOccupancyCells = std::size_t{1} << 24;  // per grid

// Cells a grid over `points` would have at `cell` metres (0 for no points).
std::size_t occupancy_cell_count(std::span<const Eigen::Vector3f> points, float cell);
// The occupancy of `points` on a grid of `cell` metres (empty for no points); throws Error(Usage)
// above kMaxOccupancyCells.
Occupancy occupancy_of(std::span<const Eigen::Vector3f> points, float cell);

// The cells of all lobes of one file: more than this is a damaged file (the writer keeps within it).
inline constexpr std::size_t kMaxOccupancyCellsPerTree = std::size_t{1} << 26;

// A lobe's surface when its file stores none (.tlobe 6.0): the alpha shape of the occupied
// cells' corners with alpha = alpha_factor x alpha_min, as the lobes themselves are made of their
// points (Livny et al. 2011, §4.2). The corners are sorted first, so the surface is the same on
// every reader. Throws Error(InvalidInput) naming `name` when no alpha shape closes, for an
// empty occupancy, more than kMaxDerivedSurfaceCells occupied cells (the writer derives only
// smaller ones; a reader's time stays bounded: an alpha shape of 8 corners per cell) or an alpha
// factor outside [1, 100].
inline constexpr std::size_t kMaxDerivedSurfaceCells = std::size_t{1} << 13;
// All derived surfaces of one file together.
inline constexpr std::size_t kMaxDerivedSurfaceCellsPerTree = std::size_t{1} << 14;
TriangleMesh surface_of_occupancy(const Occupancy& occupancy, double alpha_factor, const std::string& name);

// Coding (docs/tlobe.md, version 5): each lobe's grid (uvar cell / quantum, 0 = none; svar
// first; uvar size) stands with its lobe, and the cells of all lobes follow the lobes as one
// range-coded stream of octrees whose adaptive models the lobes share. `cell` must be a multiple
// of `quantum`.
void encode_occupancy_grid(const Occupancy& occupancy, double quantum, ByteWriter& out);
// The grid without its cells (`bits` empty), which decode_occupancy_cells then reads.
Occupancy decode_occupancy_grid(ByteReader& in, double quantum);
// The stream of the cells of `grids` (empty when none has occupancy).
std::string encode_occupancy_cells(std::span<const Occupancy* const> grids);
// Fills the cells of the grids decode_occupancy_grid read, in order; a truncated or overlong
// stream, or grids of more than kMaxOccupancyCellsPerTree cells, throw Error(InvalidInput)
// naming `name`.
void decode_occupancy_cells(std::string_view stream, std::span<Occupancy> grids, const std::string& name);
// Versions 3 and 4: the grid, then its octree as one byte of child bits per node.
Occupancy decode_occupancy_v4(ByteReader& in, double quantum);

}  // namespace treelobes::lobes
