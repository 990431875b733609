// The .tlobe file: a lobe-based tree representation (lobes/lobe_tree.hpp) in a few kilobytes.
// Layout, quantization and checksums are specified in docs/tlobe.md; in short: a 20-byte
// header (magic "TLOB", major/minor version, sizes, CRC-32 over header and payload) followed
// by a deflated payload holding the species parameters, the main skeleton (pre-order parent
// deltas, quantized positions and allometric diameters), and per lobe its seed point and its
// closed surface coded by lobes/mesh_coder.hpp, then (version 2) the lobe's occupancy
// (lobes/occupancy.hpp) on the finest grid of occupancy_cells that keeps the file within
// max_bytes.
#pragma once

#include "lobes/lobe_tree.hpp"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace treelobes::lobes {

inline constexpr std::uint8_t kTlobeMajorVersion = 4;  // 4.0 codes lobe meshes in traversal order
inline constexpr std::uint8_t kTlobeMinorVersion = 0;
inline constexpr std::uint8_t kTlobeOldestMajorVersion = 3;  // 3.1 appended the leaf area, 3.2 the lobes' leaf shares

struct TlobeOptions {
    double quantum = 0.005;            // metres: grid of skeleton positions and lobe vertices
    double diameter_quantum = 0.0005;  // metres: grid of branch diameters
    int compression_level = 9;         // deflate level 1..9
    std::size_t max_bytes = 39000;     // the occupancy grid is coarsened until the file fits (target < 40 kB)
    // Metres, finest first, steps of about 1.2 (each one costs an encoding pass).
    std::vector<double> occupancy_cells{0.03, 0.035, 0.04, 0.05, 0.06, 0.07, 0.085, 0.1, 0.12, 0.14,
                                        0.17, 0.2,   0.24, 0.3,  0.35, 0.4,  0.5,   0.6, 0.8};
    // When no grid fits, the lobe surfaces are simplified to these fractions of their faces (each
    // keeps min_lobe_faces at least) and the grids are tried again, largest fraction first (the
    // grids up to coarsest_cell_before_simplifying, then the coarser ones).
    std::vector<double> lobe_face_fractions{0.5, 0.25, 0.125, 0.0625};
    std::size_t min_lobe_faces = 12;
    // Metres: grids up to this cell are tried with every simplification of the surfaces before a
    // coarser grid, since the occupancy draws the crown's outline and the surfaces only bound it
    // (a palm at 2.9 kB: 0.35 m cells and 306 faces draw it closer than 0.8 m and 562 faces;
    // docs/rebuild.md).
    double coarsest_cell_before_simplifying = 0.5;
};

// Bytes of the file. Lobes with cluster_points get their occupancy on the finest grid of
// occupancy_cells (rounded to the quantum) at which the file fits max_bytes: the grids up to
// coarsest_cell_before_simplifying first, their surfaces simplified (lobe_face_fractions) until
// one fits, then the coarser grids the same way; if none fits even then, the most simplified
// surfaces are stored without occupancy. Lobes without cluster_points (a decoded tree) keep their occupancy as it is. Throws Error(Usage) for options out of range or coordinates the grid cannot hold.
std::string encode_tlobe(const LobeTree& tree, const TlobeOptions& options = {});
// Parses a file's bytes; any inconsistency throws Error(InvalidInput) naming `name`.
// Decoded lobes have origin 0 (the tree's frame), the skeleton the stored origin.
LobeTree decode_tlobe(std::string_view bytes, const std::string& name);
// The inflated payload behind the header, size and CRC checks (what decode_tlobe parses once
// they pass; fuzz/ feeds it directly so that mutations reach the parser). Same errors.
// `major`, `minor`: the header's version, which says how lobe meshes are coded and which
// appended fields the payload holds.
LobeTree decode_tlobe_payload(std::string_view payload, const std::string& name, int major = kTlobeMajorVersion,
                              int minor = kTlobeMinorVersion);

void write_tlobe(const LobeTree& tree, const std::filesystem::path& path, const TlobeOptions& options = {});
LobeTree read_tlobe(const std::filesystem::path& path);

}  // namespace treelobes::lobes
