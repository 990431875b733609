// The .tlobe file: a lobe-based tree representation (lobes/lobe_tree.hpp) in a few kilobytes.
// Layout, quantization and checksums are specified in docs/tlobe.md; in short: a 20-byte
// header (magic "TLOB", major/minor version, sizes, CRC-32 over header and payload) followed
// by a deflated payload holding the species parameters, the main skeleton (pre-order parent
// deltas, quantized positions and allometric diameters), and per lobe its seed point, its
// closed surface coded by lobes/mesh_coder.hpp and the grid of its occupancy
// (lobes/occupancy.hpp), then the occupied cells of all lobes range-coded (version 5), on the
// finest grid of occupancy_cells that keeps the file within max_bytes; where even the simplest
// surfaces do not fit, none is stored and the reader derives them from the occupancy (version 6).
#pragma once

#include "lobes/lobe_tree.hpp"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace treelobes::lobes {

// 5.0: lobe vertex grid of its own, occupancy range-coded; 6.0: a lobe may store no surface
// and have it derived from its occupancy (Lobe::surface_from_occupancy).
inline constexpr std::uint8_t kTlobeMajorVersion = 6;
inline constexpr std::uint8_t kTlobeMinorVersion = 0;
inline constexpr std::uint8_t kTlobeOldestMajorVersion = 3;  // 3.1 appended the leaf area, 3.2 the lobes' leaf shares

struct TlobeOptions {
    double quantum = 0.005;            // metres: grid of skeleton positions and occupancy cells
    // Metres: grid of lobe surface vertices. The surfaces only bound the occupancy, whose finest
    // cell is 3 cm, so they need no finer grid; 2 cm instead of 5 mm takes 11 % off their bytes
    // (docs/tlobe.md).
    double lobe_quantum = 0.02;
    // On an occupancy grid coarser than 8 x lobe_quantum, the lobe vertices take this fraction of
    // its cell as their grid: the surfaces only bound cells that size, and the bytes saved buy a
    // finer grid (the second palm: 0.3 m cells instead of 0.35-0.5 m in 2.9 kB; docs/tlobe.md).
    double lobe_quantum_per_cell = 0.125;
    double diameter_quantum = 0.0005;  // metres: grid of branch diameters
    // Metres: the main skeleton is stored thinned by Douglas-Peucker along its chains, each
    // dropped node within skeleton_tolerance of the segment between the kept ones around it and
    // its diameter within skeleton_diameter_tolerance of theirs interpolated (0: every node kept).
    // 3 cm rather than 1 cm: the bytes saved buy a finer occupancy grid where the budget binds
    // (the second palm over 20 seeds: 15 instead of 12 meet the crown-outline target), while the
    // real scans' points stay as close to the trees synthesized from their files: 1 mm at most
    // at the median (docs/tlobe.md).
    double skeleton_tolerance = 0.03;
    double skeleton_diameter_tolerance = 0.002;
    int compression_level = 9;         // deflate level 1..9
    std::size_t max_bytes = 39000;     // the occupancy grid is coarsened until the file fits (target < 40 kB)
    // A grid is used only when the lobes' points average at least this many per occupied cell
    // (the coarsest grid of occupancy_cells always may be): finer, the occupancy records where
    // the samples happened to fall, not where the crown is, and the leaves drawn only in its
    // cells leave holes (terminalia's 200,000 samples over a 20 m crown: 3.8 per cell at 10 cm,
    // crown outlines 0.88 / 0.84 against 0.81 / 0.79 at 6 cm; docs/rebuild.md).
    double min_points_per_cell = 6;
    // Metres, finest first, steps of about 1.2 (each one costs an encoding pass).
    std::vector<double> occupancy_cells{0.03, 0.035, 0.04, 0.05, 0.06, 0.07, 0.085, 0.1, 0.12, 0.14,
                                        0.17, 0.2, 0.22, 0.24, 0.27, 0.3, 0.35, 0.4,  0.5,   0.6, 0.8};
    // At each grid, finest first, the lobe surfaces are simplified to these fractions of their
    // faces (each keeps min_lobe_faces at least), largest fraction first, until the file fits,
    // down to the fraction number simplifications_per_grid: the occupancy draws the crown's
    // outline and the surfaces only bound it, so a finer grid is worth more than fuller surfaces,
    // down to about an eighth of the faces (the palms at 3.8 and 2.9 kB; docs/rebuild.md). The
    // further fractions are tried only when no grid fits with that, each over all the grids.
    std::vector<double> lobe_face_fractions{0.5, 0.25, 0.125, 0.0625};
    std::size_t simplifications_per_grid = 3;
    std::size_t min_lobe_faces = 12;
    // Metres: at a grid where the surfaces simplified that far still do not fit, the main
    // skeleton's bare twigs up to this long are left out before a coarser grid is tried. A bare
    // twig is a chain from a fork to a tip that seeds no lobe: a cluster with too few points for
    // a lobe, whose edges went back to the main structure (docs/lobes.md), drawn as a thin
    // cylinder with no leaves. One sample of the second palm has 40 of them (0.1-1 m, 15 m in
    // all): without them its file keeps 30 instead of 40 cm cells and meets the crown-outline
    // target (docs/rebuild.md). 0: twigs are never left out.
    double bare_twig_length = 1.0;
    // At a grid where even that does not fit, the lobes are stored without surfaces and the
    // reader derives them from the occupancy (Lobe::surface_from_occupancy, version 6.0): the
    // surfaces took 56 % of the second palm's 2.9 kB; without them its cells go from 27 to 17 cm
    // and every one of 20 samples meets the crown-outline target (docs/rebuild.md). false: the
    // surfaces are always stored.
    bool surfaces_from_occupancy = true;
};

// Bytes of the file. Lobes with cluster_points get their occupancy on the finest grid of
// occupancy_cells (rounded to the quantum) at which the file fits max_bytes, with the surfaces
// as they are or simplified (lobe_face_fractions, up to simplifications_per_grid) as far as that
// grid needs, then without the bare twigs (bare_twig_length), then with no surfaces stored, the
// reader deriving them from the occupancy (Lobe::surface_from_occupancy), then the further
// fractions the same way; if no grid fits even then, the most simplified surfaces are stored
// without occupancy. Lobes without cluster_points (a decoded tree) keep their occupancy as it
// is. Throws Error(Usage) for options out of range or coordinates the grid cannot hold.
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
