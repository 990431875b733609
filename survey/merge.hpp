// Joining the per-tile results of `treelobes tile` / `treelobes batch` into one survey result.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::survey {

// The tile folders under `dirs`: a folder with summary.json and trees.csv is a tile (a `tile`
// run); any other folder is a batch output whose subfolders are its tiles, and there only the
// tiles with a completion marker count (the others are returned in `incomplete`). Sorted by
// tile name. Throws Error(InvalidInput) when a folder is missing or two tiles share a name.
struct TileFolders {
    std::vector<std::filesystem::path> complete;
    std::vector<std::string> incomplete;               // names of batch tiles without a completion marker
    std::vector<std::filesystem::path> failure_lists;  // the batches' failures*.jsonl
};
TileFolders find_tile_folders(const std::vector<std::filesystem::path>& dirs);

struct MergedSurvey {
    std::string trees_csv;             // global_id,tile, then the tiles' columns
    std::string trees_geojson;         // the tiles' features with global_id and tile properties
    std::string crowns_geojson;        // the same with the crown outlines (the tiles' crowns.geojson)
    std::vector<std::uint8_t> forest;  // every tree, named by its global id
    std::string summary_json;          // tiles, summed counts, CRS, options; no paths or timings
    std::string failures_jsonl;        // the batches' tile failures, sorted; empty when none
    // Survey-wide ids found in more than one tile ("<id> in <tile>, <tile>"): one tree modelled
    // by two tiles, which happens when tiles are run without --buffer.
    std::vector<std::string> duplicated_ids;
    // Survey-wide ids of the trees that reached their tile's buffer edge (buffer.trees_at_edge of
    // the tiles' summaries), sorted: they may have been cut there.
    std::vector<std::string> trees_at_buffer_edge;
    std::size_t tiles = 0, trees = 0;
};

// Trees are sorted by their survey-wide id (the tiles' global_id column, from the stem base;
// survey/tree_id.hpp), then by tile.
// Order-independent: the same folders in any order give the same bytes. Throws
// Error(InvalidInput) when tiles disagree on the CSV columns, the CRS or the DBF6 options.
MergedSurvey merge_tiles(const TileFolders& folders);

}  // namespace treelobes::survey
