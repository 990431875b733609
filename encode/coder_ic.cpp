#include "encode/coder_ic.hpp"

#include "core/error.hpp"
#include "encode/bitstream.hpp"
#include "encode/bwt.hpp"
#include "encode/interpolative.hpp"
#include "encode/transforms.hpp"

#include <algorithm>
#include <climits>

namespace treelobes::encode {

namespace {

constexpr unsigned kAlphabet = 9;  // symbols 0..8 (Table 1)
constexpr std::uint64_t kMaxMtfPosition = kAlphabet - 1;
// Radius d-gaps are differences of two ints, so shifted or zig-zagged gaps stay below 2^34.
constexpr std::uint64_t kMaxShiftedGap = std::uint64_t{1} << 34;

// Internode index ranges [begin, end) of the branches: each ends at the internode closed by a 7;
// internodes after the last 7 (only in codes that do not end with one) form a final sublist.
std::vector<std::pair<std::size_t, std::size_t>> branch_sublists(const std::string& symbols) {
    std::vector<std::pair<std::size_t, std::size_t>> lists;
    std::size_t begin = 0, internode = 0;
    for (char c : symbols) {
        if (!is_terminator(c)) continue;
        ++internode;
        if (c == kTip) {
            lists.emplace_back(begin, internode);
            begin = internode;
        }
    }
    if (begin < internode) lists.emplace_back(begin, internode);
    return lists;
}

std::size_t internode_count(const std::string& symbols) {
    return static_cast<std::size_t>(std::count_if(symbols.begin(), symbols.end(), is_terminator));
}

}  // namespace

namespace {

std::vector<std::uint8_t> write_symbols_with(const std::string& symbols, const BwtResult& bwt, MtfRule rule) {
    BitWriter out;
    write_count(out, symbols.size());
    write_centred_minimal_binary(out, bwt.primary_index, symbols.size() + 1);
    out.write_bit(rule == MtfRule::Mtf2);
    const std::vector<std::uint8_t> mtf = mtf_encode(bwt.last_column, kAlphabet, rule);
    const std::vector<std::uint64_t> values(mtf.begin(), mtf.end());
    write_interpolative(out, cumulative_sum(values), {.max_gap = kMaxMtfPosition});
    return out.take();
}

}  // namespace

std::vector<std::uint8_t> ic_encode_symbols(const std::string& symbols) {
    if (symbols.empty()) {
        BitWriter out;
        write_count(out, 0);
        return out.take();
    }
    std::vector<std::uint8_t> text(symbols.size());
    for (std::size_t i = 0; i < symbols.size(); ++i) text[i] = static_cast<std::uint8_t>(symbols[i] - '0');
    const BwtResult bwt = bwt_forward(text, kAlphabet);
    // MTF as printed, or MTF-2 when that is smaller (it is on every tree of docs/dbf6.md).
    std::vector<std::uint8_t> printed = write_symbols_with(symbols, bwt, MtfRule::ToFront);
    std::vector<std::uint8_t> mtf2 = write_symbols_with(symbols, bwt, MtfRule::Mtf2);
    return mtf2.size() < printed.size() ? mtf2 : printed;
}

std::string ic_decode_symbols(std::span<const std::uint8_t> bytes, const std::string& context) {
    BitReader in(bytes, context);
    const std::uint64_t n = read_count(in);
    if (n > kMaxCodeSymbols) in.fail("code length " + std::to_string(n) + " exceeds the decoder limit");
    if (n == 0) return {};
    const std::uint64_t primary = read_centred_minimal_binary(in, n + 1);
    const MtfRule rule = in.read_bit() ? MtfRule::Mtf2 : MtfRule::ToFront;
    const std::vector<std::uint64_t> sums = read_interpolative(in, n, {.max_gap = kMaxMtfPosition});
    const std::vector<std::uint64_t> values = differences(sums, kMaxMtfPosition, context);
    const std::vector<std::uint8_t> mtf(values.begin(), values.end());
    const std::vector<std::uint8_t> text = bwt_inverse(mtf_decode(mtf, kAlphabet, context, rule), primary, kAlphabet, context);
    std::string symbols(text.size(), '0');
    for (std::size_t i = 0; i < text.size(); ++i) symbols[i] = static_cast<char>('0' + text[i]);
    return symbols;
}

std::vector<std::int64_t> radius_gaps(const std::string& symbols, std::span<const int> radii, std::int64_t offset) {
    std::vector<std::int64_t> gaps;
    gaps.reserve(radii.size());
    for (const auto& [begin, end] : branch_sublists(symbols)) {
        std::int64_t previous = 0;  // the inverted sublist starts from 0
        for (std::size_t i = end; i-- > begin;) {
            const std::int64_t aligned = static_cast<std::int64_t>(radii[i]) - offset;
            gaps.push_back(aligned - previous);
            previous = aligned;
        }
    }
    return gaps;
}

RadiiSequence radii_to_sequence(const std::string& symbols, std::span<const int> radii, GapMap map) {
    RadiiSequence sequence;
    sequence.map = map;
    if (radii.empty()) return sequence;
    sequence.offset = *std::min_element(radii.begin(), radii.end());
    const std::vector<std::int64_t> gaps = radius_gaps(symbols, radii, sequence.offset);
    const std::int64_t lowest = *std::min_element(gaps.begin(), gaps.end());
    sequence.shift = lowest < 0 ? static_cast<std::uint64_t>(-lowest) : 0;
    std::vector<std::uint64_t> mapped(gaps.size());
    for (std::size_t i = 0; i < gaps.size(); ++i)
        mapped[i] = map == GapMap::ZigZag ? zigzag(gaps[i]) : static_cast<std::uint64_t>(gaps[i]) + sequence.shift;
    sequence.cumulative = cumulative_sum(mapped);
    return sequence;
}

namespace {

std::vector<std::uint8_t> write_radii(const RadiiSequence& sequence) {
    std::uint64_t max_gap = 0, previous = 0;
    for (std::uint64_t q : sequence.cumulative) {
        max_gap = std::max(max_gap, q - previous);
        previous = q;
    }
    BitWriter out;
    write_count(out, zigzag(sequence.offset));
    out.write_bit(sequence.map == GapMap::ZigZag);
    if (sequence.map == GapMap::Shift) write_count(out, sequence.shift);
    write_count(out, max_gap);
    write_interpolative(out, sequence.cumulative, {.max_gap = max_gap});
    return out.take();
}

}  // namespace

std::vector<std::uint8_t> ic_encode_radii(const std::string& symbols, std::span<const int> radii) {
    if (radii.size() != internode_count(symbols))
        throw Error(ExitCode::Internal, "ic radii: radius count differs from the internode count");
    if (radii.empty()) return {};
    const RadiiSequence shifted = radii_to_sequence(symbols, radii, GapMap::Shift);
    std::vector<std::uint8_t> bytes = write_radii(shifted);
    if (shifted.shift == 0) return bytes;  // monotone: the printed scheme, nothing to choose
    std::vector<std::uint8_t> zigzagged = write_radii(radii_to_sequence(symbols, radii, GapMap::ZigZag));
    return zigzagged.size() < bytes.size() ? zigzagged : bytes;
}

std::vector<int> ic_decode_radii(std::span<const std::uint8_t> bytes, const std::string& symbols, const std::string& context) {
    const std::size_t n = internode_count(symbols);
    std::vector<int> radii(n);
    if (n == 0) {
        if (!bytes.empty()) throw Error::input(context, "radii stream for a code without internodes");
        return radii;
    }
    BitReader in(bytes, context);
    const std::int64_t offset = unzigzag(read_count(in));
    const bool zigzagged = in.read_bit();
    const std::uint64_t shift = zigzagged ? 0 : read_count(in);
    const std::uint64_t max_gap = read_count(in);
    constexpr std::int64_t kLimit = std::int64_t{1} << 33;  // radii are ints: offsets and gaps stay below
    if (max_gap > kMaxShiftedGap || shift > kMaxShiftedGap || offset < -kLimit || offset > kLimit)
        in.fail("radius gap bounds out of range");
    const std::vector<std::uint64_t> mapped = differences(read_interpolative(in, n, {.max_gap = max_gap}), max_gap, context);
    std::size_t k = 0;
    for (const auto& [begin, end] : branch_sublists(symbols)) {
        std::int64_t value = 0;
        for (std::size_t i = end; i-- > begin;) {
            const std::uint64_t m = mapped[k++];
            value += zigzagged ? unzigzag(m) : static_cast<std::int64_t>(m) - static_cast<std::int64_t>(shift);
            const std::int64_t radius = value + offset;
            if (radius < INT_MIN || radius > INT_MAX) in.fail("decoded radius out of range");
            radii[i] = static_cast<int>(radius);
        }
    }
    return radii;
}

}  // namespace treelobes::encode
