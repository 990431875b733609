// Which tiles a batch runs, in which order, and which of them one shard takes.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::survey {

// The tiles named by `source`, sorted by path (byte order) without duplicates:
//   a folder   its point-cloud files (.las .ply .pcd .xyz .csv .pts .asc), not recursive;
//   a pattern  with * ? or [ : the files matching it (glob(3), e.g. "tiles/*.las");
//   a list     a file with any other extension (.txt, .list, ...): one path per line, relative
//              to the list's folder; blank lines and lines starting with # are skipped;
//   a tile     a single point-cloud file.
// Throws Error(InvalidInput) when the source is missing, a listed file does not exist or no tile
// is found, and Error(Usage) when two tiles share a name (their output folders would collide).
std::vector<std::filesystem::path> list_tiles(const std::string& source);

// The name of a tile's output folder: its file name without the extension.
std::string tile_name(const std::filesystem::path& tile);

struct Shard {
    std::size_t index = 0;  // 0 .. count - 1
    std::size_t count = 1;
};
// "i/n" with 0 <= i < n (Slurm: $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT); Error(Usage) otherwise.
Shard parse_shard(const std::string& text);
// Every count-th tile starting at index: shards are disjoint and together take every tile.
std::vector<std::filesystem::path> shard_tiles(const std::vector<std::filesystem::path>& tiles, const Shard& shard);

}  // namespace treelobes::survey
