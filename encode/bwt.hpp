// Burrows–Wheeler transform (Burrows & Wheeler 1994) over small integer alphabets, with the
// primary index that makes it invertible, plus the suffix array it is computed from.
//
// Convention: the transform of S is the last column of the sorted rotations of S$, where $ is a
// unique sentinel smaller than every symbol, with the $ removed; the primary index is the row at
// which the $ stood. Sorting the rotations of S$ equals sorting the suffixes of S$, so one
// suffix array gives the transform in O(n log n) (prefix doubling with radix sort).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes::encode {

// Suffix array of `text` (symbols < alphabet_size): start positions of its suffixes in
// lexicographic order, a proper prefix sorting before the longer suffix. O(n log n).
std::vector<std::uint32_t> suffix_array(std::span<const std::uint8_t> text, unsigned alphabet_size);

struct BwtResult {
    std::vector<std::uint8_t> last_column;  // n symbols
    std::size_t primary_index = 0;          // in [0, n]: row of the removed sentinel
};

BwtResult bwt_forward(std::span<const std::uint8_t> text, unsigned alphabet_size);

// Inverts bwt_forward in O(n). Throws Error(InvalidInput) naming `context` when a symbol is not
// below alphabet_size or the primary index does not give a single cycle through all n symbols.
std::vector<std::uint8_t> bwt_inverse(std::span<const std::uint8_t> last_column, std::size_t primary_index, unsigned alphabet_size,
                                      const std::string& context);

}  // namespace treelobes::encode
