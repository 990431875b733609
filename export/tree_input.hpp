// What `treelobes export` reads: our own tree outputs, as skeletons (+ lobes, species) in world
// coordinates. A skeleton PLY, a .tlobe (skeleton, lobes and species), a .dbf6 (one LOD of a
// chain-coded tree), a .forest (one LOD of every tree, placed), or a folder holding any of those
// (read recursively in sorted path order; other files are skipped), so a tile output folder
// exports as one set of trees.
#pragma once

#include "core/tree_graph.hpp"
#include "core/triangle_mesh.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace treelobes::exporting {

struct ExportTree {
    std::string name;                 // file stem, or the tree's name in a .forest
    TreeGraph skeleton;               // world position = skeleton.origin + node position
    std::vector<TriangleMesh> lobes;  // closed crown lobes (.tlobe), origin = skeleton.origin
    std::string species;              // empty when unknown
    // Reconstruction confidence in [0, 1]: the share of the tree's points on high-confidence
    // skeleton edges (Livny et al. 2011, §4.2: an internode whose points lie on average within the
    // lobe-confidence diameter d' = f_s d(u) of it); the rest formed the low-confidence clusters
    // that became lobes. Known for a .tlobe with the record its pipeline wrote beside it (see
    // tree_confidence); unset otherwise.
    std::optional<double> confidence;
};

struct ExportInput {
    std::vector<ExportTree> trees;
    std::string crs;                 // from the inputs' georef sidecars ("" when unknown)
    std::vector<std::string> files;  // files the trees came from
};

// `lod` selects the LOD of .dbf6 and .forest inputs (0 = full detail). Throws Error(InvalidInput)
// naming the file for unreadable or invalid input (a truncated file, a skeleton that is not one
// rooted tree), also for a folder without any tree file; Error(Usage) for a LOD not stored.
ExportInput read_export_input(const std::filesystem::path& path, int lod = 0);

// The confidence of the tree in `tlobe` whose lobes hold `lobe_points` scan points, from the
// record beside it: `<stem>.json` of `treelobes tile` (its "points": all points of the tree) or
// `<stem>_lobes.json` of `treelobes lobes` ("points": {"main", "lobes"}): 1 - lobe points / tree
// points. nullopt when neither record is there or it has no points; Error(InvalidInput) naming
// the record when it is not JSON.
std::optional<double> tree_confidence(const std::filesystem::path& tlobe, std::size_t lobe_points);

// True for the file kinds read_export_input takes (by extension; PLY: a skeleton PLY).
bool is_tree_file(const std::filesystem::path& path);

}  // namespace treelobes::exporting
