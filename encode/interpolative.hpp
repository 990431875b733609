// Binary interpolative coding (Moffat & Stuiver 2000) of non-decreasing integer sequences, as
// used by Strnad et al. 2020, §2.3/§3.3: the middle element of a run whose two end values are known lies in
// [left end, right end]; it is coded in that range and both halves are coded recursively.
// With a known maximum gap g between neighbours the range shrinks further to
// [right - (b - m)·g, left + (m - a)·g] ∩ [left, right]. Middle values are coded with the
// centred minimal binary code (FELICS), or with plain ceil(log2(range)) bits as printed in §2.3.
#pragma once

#include "encode/bitstream.hpp"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace treelobes::encode {

inline constexpr std::uint64_t kNoGapBound = std::numeric_limits<std::uint64_t>::max();

enum class MiddleCode {
    CentredMinimalBinary,  // default: short codes near the centre of the range
    FixedBinary,           // ceil(log2(range)) bits, the plain code of the §2.3 example
};

struct InterpolativeOptions {
    std::uint64_t max_gap = kNoGapBound;  // known bound on values[i] - values[i-1], if any
    MiddleCode middle_code = MiddleCode::CentredMinimalBinary;
};

// One coded middle element (for tests and statistics).
struct InterpolativeStep {
    std::size_t index = 0;
    std::uint64_t low = 0, high = 0;  // the range the value was coded in
    unsigned bits = 0;
};

// Codes the elements strictly between positions `first` and `last` of a non-decreasing
// sequence whose values at `first` and `last` the decoder already knows. Appends a step per
// coded element to `trace` when given (in coding order).
void write_interpolative_between(BitWriter& out, std::span<const std::uint64_t> values, std::size_t first, std::size_t last,
                                 const InterpolativeOptions& options, std::vector<InterpolativeStep>* trace = nullptr);
// Fills values[first+1 .. last-1] given values[first] and values[last].
void read_interpolative_between(BitReader& in, std::span<std::uint64_t> values, std::size_t first, std::size_t last,
                                const InterpolativeOptions& options);

// A whole sequence of known length n >= 0 with values >= 0: a virtual element 0 precedes it,
// the last value is written with an Elias delta code, the rest interpolatively.
void write_interpolative(BitWriter& out, std::span<const std::uint64_t> values, const InterpolativeOptions& options);
// Throws Error(InvalidInput) (via `in`) for truncated data or values that break the bounds.
std::vector<std::uint64_t> read_interpolative(BitReader& in, std::size_t n, const InterpolativeOptions& options);

}  // namespace treelobes::encode
