// `treelobes info` on the files treelobes itself writes: `.dbf6` trees (Strnad et al. 2020 chain
// codes with their levels of detail), `.forest` files (many placed trees, docs/forest.md) and
// `.tlobe` lobe trees (Livny et al. 2011, docs/tlobe.md). What a user asks of them first: what is
// inside, how big each part is, and where it stands. The point, mesh and skeleton formats are
// described by core/file_info.hpp.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

namespace treelobes::cli {

// True for the extensions .dbf6, .forest and .tlobe (any case).
bool is_product_file(const std::filesystem::path& path);

// The file's description as JSON (the `info --json` entry; print_product_file shows it). Throws
// Error(InvalidInput) for a missing, damaged or truncated file, as the readers do.
nlohmann::json describe_product_file(const std::filesystem::path& path);

// A few lines for people, from describe_product_file's JSON.
void print_product_file(const nlohmann::json& info);

}  // namespace treelobes::cli
