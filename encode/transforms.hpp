// Small reversible transforms of the interpolative pipeline (Strnad et al. 2020, §3.3): move-to-front
// (Ryabko 1980) and the cumulative sum that turns small non-negative values into the
// non-decreasing sequence binary interpolative coding needs.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes::encode {

// How a coded symbol moves in the table.
enum class MtfRule : std::uint8_t {
    ToFront,  // move-to-front (Ryabko 1980), as Strnad et al. 2020, §3.3 prints it
    // MTF-2 (Balkenhol, Kurtz & Shtarkov 1999): a symbol found at position 1 goes to the front only
    // when the previous position was not 0, and a symbol found further back goes to position 1.
    // A symbol that interrupts a run of the front symbol once then no longer displaces it, so the
    // long runs of the BWT output keep their zeros.
    Mtf2,
};

// Move-to-front over the alphabet 0..alphabet_size-1 with the table initially in natural order:
// each symbol is replaced by its current table position and then moved up by `rule`. Runs of
// one symbol (the BWT makes many) become runs of zeros.
std::vector<std::uint8_t> mtf_encode(std::span<const std::uint8_t> symbols, unsigned alphabet_size, MtfRule rule = MtfRule::ToFront);
// Throws Error(InvalidInput) naming `context` for a position not below alphabet_size.
std::vector<std::uint8_t> mtf_decode(std::span<const std::uint8_t> positions, unsigned alphabet_size, const std::string& context,
                                     MtfRule rule = MtfRule::ToFront);

// Q[i] = v[0] + ... + v[i].
std::vector<std::uint64_t> cumulative_sum(std::span<const std::uint64_t> values);
// The inverse: v[i] = Q[i] - Q[i-1] (Q[-1] = 0). Throws Error(InvalidInput) naming `context`
// when Q decreases or a difference exceeds max_difference.
std::vector<std::uint64_t> differences(std::span<const std::uint64_t> sums, std::uint64_t max_difference, const std::string& context);

}  // namespace treelobes::encode
