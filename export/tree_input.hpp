// What `treelobes export` reads: our own tree outputs, as skeletons (+ lobes, species) in world
// coordinates. A skeleton PLY, a .tlobe (skeleton, lobes and species), a .dbf6 (one LOD of a
// chain-coded tree), a .forest (one LOD of every tree, placed), or a folder holding any of those
// (read recursively in sorted path order; other files are skipped), so a tile output folder
// exports as one set of trees.
#pragma once

#include "core/tree_graph.hpp"
#include "core/triangle_mesh.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::exporting {

struct ExportTree {
    std::string name;                 // file stem, or the tree's name in a .forest
    TreeGraph skeleton;               // world position = skeleton.origin + node position
    std::vector<TriangleMesh> lobes;  // closed crown lobes (.tlobe), origin = skeleton.origin
    std::string species;              // empty when unknown
};

struct ExportInput {
    std::vector<ExportTree> trees;
    std::string crs;                  // from the inputs' georef sidecars ("" when unknown)
    std::vector<std::string> files;   // files the trees came from
};

// `lod` selects the LOD of .dbf6 and .forest inputs (0 = full detail). Throws Error(InvalidInput)
// naming the file for unreadable or invalid input (a truncated file, a skeleton that is not one
// rooted tree), also for a folder without any tree file; Error(Usage) for a LOD not stored.
ExportInput read_export_input(const std::filesystem::path& path, int lod = 0);

// True for the file kinds read_export_input takes (by extension; PLY: a skeleton PLY).
bool is_tree_file(const std::filesystem::path& path);

}  // namespace treelobes::exporting
