// The `ic` coder: seed 000 §3.3 as printed, with the refinements of §2.3.
//   symbols: C -> BWT (primary index kept) -> MTF -> cumulative sum -> interpolative coding with
//            the known maximum gap 8 (the largest MTF position of a 9-symbol alphabet);
//   radii:   per-branch sublists (a branch ends at its 7) inverted -> d-gaps (the first from 0)
//            -> concatenated -> minus the smallest gap (offset stored, so non-monotone radii with
//            negative gaps stay lossless) -> cumulative sum -> interpolative coding with the
//            largest shifted gap as bound.
#pragma once

#include "encode/coder.hpp"

namespace treelobes::encode {

std::vector<std::uint8_t> ic_encode_symbols(const std::string& symbols);
std::string ic_decode_symbols(std::span<const std::uint8_t> bytes, const std::string& context);

// The radii of the internodes of `symbols` (one per 6, 7 or 8).
std::vector<std::uint8_t> ic_encode_radii(const std::string& symbols, std::span<const int> radii);
std::vector<int> ic_decode_radii(std::span<const std::uint8_t> bytes, const std::string& symbols,
                                 const std::string& context);

// The non-decreasing sequence Q the radii are coded as (exposed for tests and Fig. 9).
struct RadiiSequence {
    std::int64_t offset = 0;                 // the smallest d-gap, subtracted from all of them
    std::vector<std::uint64_t> cumulative;   // Q
};
RadiiSequence radii_to_sequence(const std::string& symbols, std::span<const int> radii);

}  // namespace treelobes::encode
