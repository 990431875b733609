// The completion marker of a tile in a batch: written atomically as the last file of the tile's
// folder, so a folder without it (a killed or failed run) is never taken for a finished tile.
#pragma once

#include <filesystem>
#include <string>

namespace treelobes::survey {

inline constexpr const char* kCompletionMarker = "batch_done.json";

// `key` states what made the outputs (the input and the tile options): a folder finished with
// another key is not complete for this run.
void mark_complete(const std::filesystem::path& tile_dir, const std::string& key, int exit_code);
bool is_complete(const std::filesystem::path& tile_dir, const std::string& key);
// Exit code the finished tile had (0, or 3 when some of its trees failed); -1 when not complete.
int completed_exit_code(const std::filesystem::path& tile_dir);

}  // namespace treelobes::survey
