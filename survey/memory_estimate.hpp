// Whether a tile fits in memory, decided from its file header before it is loaded.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

namespace treelobes::survey {

// Points of a file as its header states them: LAS (the 64-bit count of LAS 1.4, else the legacy
// one) and PLY (element vertex); for formats without a count (PCD is read by PCL, text has no
// header) the file size over 24 bytes, the shortest usual text row. Throws Error(InvalidInput)
// for a missing file or a LAS/PLY file without a readable header.
std::size_t header_point_count(const std::filesystem::path& path);

// Peak memory of `treelobes tile` per input point, measured on synthetic tiles (docs/survey.md):
// the cloud, its labelled copy for points.las, terrain and segmentation arrays and the per-tree
// inputs. The estimate is points * this.
inline constexpr double kTileBytesPerPoint = 600.0;

// The default budget: half of the physical memory (so that two workers of a 2-core node fit).
double default_memory_budget_bytes();

// "--max-memory" text: a number with an optional unit K, M, G or T (powers of 1024), e.g. "4G".
// Error(Usage) for anything else or a value <= 0.
double parse_memory_size(const std::string& text);

// Peak memory of `treelobes retile` per input point: every tile is held until all inputs are read
// (one PointCloud point with its attributes, about 50 bytes), plus the input being read and
// its per-tile copies.
inline constexpr double kRetileBytesPerPoint = 160.0;

// nullopt when `points` at `bytes_per_point` fit in the budget; otherwise the message that refuses
// them: the estimate, the budget and what to do (retile smaller, or raise --max-memory).
std::optional<std::string> memory_refusal(std::size_t points, double bytes_per_point, double budget_bytes);
// The same for one tile of a batch, from its header's point count, before it is loaded.
std::optional<std::string> refuse_if_too_big(const std::filesystem::path& tile, double budget_bytes);

}  // namespace treelobes::survey
