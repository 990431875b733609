// Refusing inputs that cannot fit in memory before anything is allocated: a header that
// promises more points than the machine holds is reported with the estimate, instead of the
// reader being killed by the kernel half-way through (or a batch losing every other tree).
// The one memory estimate of treelobes: the readers check their allocations against
// memory_limit(); the commands that take --max-memory (tile, batch, retile) check a file's
// header point count times a measured peak per point against a budget before reading it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace treelobes {

// Bytes the readers may plan for: the physical memory of the machine, or TREELOBES_MAX_MEMORY
// (a byte count with an optional K, M, G or T suffix, powers of 1024) when that is set and smaller.
std::uint64_t memory_limit();

// Throws Error(InvalidInput) "<file>: <what> needs about N GiB of memory, more than the M GiB
// this machine has (...)" when `bytes` exceeds memory_limit().
void check_memory_estimate(std::uint64_t bytes, const std::string& file, const std::string& what);

// A memory size such as "8G", "512m", "1.5G" or "1000000": a positive number with an optional
// unit K, M, G or T (powers of 1024). Throws Error(Usage) naming `setting` (e.g. "--max-memory")
// for anything else.
double parse_memory_size(const std::string& text, const std::string& setting = "--max-memory");

// The default --max-memory: half of memory_limit() (so that two workers of a 2-core node fit).
double default_memory_budget_bytes();

// Peak memory of `treelobes tile` per input point (buffer points included), measured on
// synthetic tiles (docs/survey.md): the cloud, its labelled copy for points.las, terrain and
// segmentation arrays and the per-tree inputs.
inline constexpr double kTileBytesPerPoint = 600.0;
// Peak memory of `treelobes retile` per input point: every tile is held until all inputs are
// read (one point with its attributes, about 50 bytes), plus the input being read and its copies.
inline constexpr double kRetileBytesPerPoint = 160.0;

// nullopt when `points` at `bytes_per_point` fit in `budget_bytes`; otherwise the message that
// refuses them: the estimate, the budget and what to do (retile smaller, or raise --max-memory).
std::optional<std::string> memory_refusal(std::size_t points, double bytes_per_point, double budget_bytes);

}  // namespace treelobes
