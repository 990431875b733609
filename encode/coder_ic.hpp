// The `ic` coder: Strnad et al. 2020, §3.3 as printed, with the refinements of §2.3.
//   symbols: C -> BWT (primary index kept) -> MTF -> cumulative sum -> interpolative coding with
//            the known maximum gap 8 (the largest MTF position of a 9-symbol alphabet). The MTF
//            step is either the printed move-to-front or MTF-2 (transforms.hpp), whichever codes
//            smaller (one bit after the primary index): MTF-2 keeps the BWT's runs longer and
//            saves 1.9-6.4 % of the symbol bytes on our trees (docs/dbf6.md);
//   radii:   zero-aligned by the smallest radius (offset stored) -> per-branch sublists (a branch
//            ends at its 7) inverted -> d-gaps (the first from 0) -> concatenated -> cumulative
//            sum -> interpolative coding with the largest gap as bound.
//            Radii that grow toward a tip (real reconstructions are not monotone) give negative
//            gaps; the coder then maps the gaps to non-negative values either by adding the
//            magnitude of the most negative one (`shift`) or by the zig-zag map 0,-1,1,-2,...
//            (`zigzag`), whichever codes smaller, and stores the choice. Monotone radii use
//            neither, exactly as printed in §3.3.
#pragma once

#include "encode/coder.hpp"

namespace treelobes::encode {

std::vector<std::uint8_t> ic_encode_symbols(const std::string& symbols);
std::string ic_decode_symbols(std::span<const std::uint8_t> bytes, const std::string& context);

// The radii of the internodes of `symbols` (one per 6, 7 or 8).
std::vector<std::uint8_t> ic_encode_radii(const std::string& symbols, std::span<const int> radii);
std::vector<int> ic_decode_radii(std::span<const std::uint8_t> bytes, const std::string& symbols, const std::string& context);

enum class GapMap : std::uint8_t {
    Shift = 0,   // gap + shift, shift = -(most negative gap) (0 for monotone radii)
    ZigZag = 1,  // 0, -1, 1, -2, 2 ... -> 0, 1, 2, 3, 4 ...
};

// The non-decreasing sequence Q the radii are coded as (exposed for tests and Fig. 9).
struct RadiiSequence {
    std::int64_t offset = 0;  // the smallest radius, subtracted from all of them
    GapMap map = GapMap::Shift;
    std::uint64_t shift = 0;                // for GapMap::Shift
    std::vector<std::uint64_t> cumulative;  // Q
};
RadiiSequence radii_to_sequence(const std::string& symbols, std::span<const int> radii, GapMap map);
// The signed d-gaps of the zero-aligned, inverted branch sublists, concatenated (step 1-3).
std::vector<std::int64_t> radius_gaps(const std::string& symbols, std::span<const int> radii, std::int64_t offset);

}  // namespace treelobes::encode
