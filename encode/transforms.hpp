// Small reversible transforms of the interpolative pipeline (seed 000 §3.3): move-to-front
// (Ryabko 1980) and the cumulative sum that turns small non-negative values into the
// non-decreasing sequence binary interpolative coding needs.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes::encode {

// Move-to-front over the alphabet 0..alphabet_size-1 with the table initially in natural order:
// each symbol is replaced by its current table position and then moved to the front. Runs of one
// symbol (the BWT makes many) become runs of zeros.
std::vector<std::uint8_t> mtf_encode(std::span<const std::uint8_t> symbols, unsigned alphabet_size);
// Throws Error(InvalidInput) naming `context` for a position not below alphabet_size.
std::vector<std::uint8_t> mtf_decode(std::span<const std::uint8_t> positions, unsigned alphabet_size,
                                     const std::string& context);

// Q[i] = v[0] + ... + v[i].
std::vector<std::uint64_t> cumulative_sum(std::span<const std::uint64_t> values);
// The inverse: v[i] = Q[i] - Q[i-1] (Q[-1] = 0). Throws Error(InvalidInput) naming `context`
// when Q decreases or a difference exceeds max_difference.
std::vector<std::uint64_t> differences(std::span<const std::uint64_t> sums, std::uint64_t max_difference,
                                       const std::string& context);

}  // namespace treelobes::encode
