// Coding primitives of the compression issue: bit IO, Elias and centred minimal binary codes,
// BWT, MTF, cumulative sums and binary interpolative coding (Strnad et al. 2020, §2.3 worked example).
#include "core/error.hpp"
#include "encode/bitstream.hpp"
#include "encode/bwt.hpp"
#include "encode/interpolative.hpp"
#include "core/range_coder.hpp"
#include "encode/transforms.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

std::vector<std::uint8_t> random_symbols(std::mt19937& rng, std::size_t n, unsigned alphabet) {
    std::vector<std::uint8_t> s(n);
    for (auto& c : s) c = static_cast<std::uint8_t>(rng() % alphabet);
    return s;
}

// Sorting all suffixes by brute force: the reference for the suffix array.
std::vector<std::uint32_t> naive_suffix_array(const std::vector<std::uint8_t>& text) {
    std::vector<std::uint32_t> sa(text.size() + 1);
    for (std::uint32_t i = 0; i < sa.size(); ++i) sa[i] = i;
    std::sort(sa.begin(), sa.end(), [&](std::uint32_t a, std::uint32_t b) {
        return std::lexicographical_compare(text.begin() + a, text.end(), text.begin() + b, text.end());
    });
    return sa;
}

unsigned ceil_log2(std::uint64_t n) { return n <= 1 ? 0 : static_cast<unsigned>(std::ceil(std::log2(static_cast<double>(n)))); }

// A non-decreasing Q[1..45] (stored 0-based) with Q[1] = 18, Q[23] = middle, Q[45] = 106.
std::vector<std::uint64_t> section_2_3_sequence(std::uint64_t middle) {
    std::vector<std::uint64_t> q(45);
    for (std::size_t i = 0; i < 45; ++i) {
        if (i <= 22)
            q[i] = 18 + (middle - 18) * i / 22;
        else
            q[i] = middle + (106 - middle) * (i - 22) / 22;
    }
    return q;
}

}  // namespace

TEST(BitStream, WritesAndReadsMixedWidths) {
    BitWriter out;
    out.write(0b101, 3);
    out.write(0xDEADBEEFCAFEBABEull, 64);
    out.write(1, 1);
    out.write(0x3FF, 10);
    EXPECT_EQ(out.bit_count(), 78u);
    BitReader in(out.bytes(), "test");
    EXPECT_EQ(in.read(3), 0b101u);
    EXPECT_EQ(in.read(64), 0xDEADBEEFCAFEBABEull);
    EXPECT_EQ(in.read(1), 1u);
    EXPECT_EQ(in.read(10), 0x3FFu);
    EXPECT_EQ(in.bits_left(), 2u);  // padding of the last byte
}

TEST(BitStream, ReadingPastTheEndThrows) {
    const std::vector<std::uint8_t> bytes{0xFF};
    BitReader in(bytes, "stream.bin");
    in.read(6);
    try {
        in.read(3);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("stream.bin"), std::string::npos);
    }
}

TEST(BitStream, EliasCodesRoundTripAndRejectGarbage) {
    const std::vector<std::uint64_t> values{1, 2, 3, 4, 7, 8, 1000, 123456789, (1ull << 40) + 3, UINT64_MAX};
    BitWriter out;
    for (auto v : values) write_elias_gamma(out, v);
    for (auto v : values) write_elias_delta(out, v);
    for (auto v : values) write_count(out, v - 1);
    BitReader in(out.bytes(), "test");
    for (auto v : values) EXPECT_EQ(read_elias_gamma(in), v);
    for (auto v : values) EXPECT_EQ(read_elias_delta(in), v);
    for (auto v : values) EXPECT_EQ(read_count(in), v - 1);
    // Gamma lengths: 2*floor(log2 v) + 1.
    BitWriter one;
    write_elias_gamma(one, 9);
    EXPECT_EQ(one.bit_count(), 7u);
    // All-zero input: no terminating one within 64 bits -> error, not a loop.
    const std::vector<std::uint8_t> zeros(16, 0);
    BitReader bad(zeros, "zeros");
    EXPECT_THROW(read_elias_gamma(bad), Error);
}

TEST(CentredMinimalBinary, ShortCodesSitInTheCentre) {
    // n = 89 (the §2.3 range [18, 106]): 2^7 - 89 = 39 values get 6 bits, 50 get 7.
    int short_codes = 0;
    for (std::uint64_t x = 0; x < 89; ++x) {
        const unsigned length = centred_minimal_binary_length(x, 89);
        EXPECT_TRUE(length == 6 || length == 7);
        short_codes += length == 6;
    }
    EXPECT_EQ(short_codes, 39);
    EXPECT_EQ(centred_minimal_binary_length(44, 89), 6u);  // centre
    EXPECT_EQ(centred_minimal_binary_length(0, 89), 7u);   // ends
    EXPECT_EQ(centred_minimal_binary_length(88, 89), 7u);
    EXPECT_EQ(centred_minimal_binary_length(0, 1), 0u);
    for (std::uint64_t n : {1ull, 2ull, 3ull, 5ull, 8ull, 89ull, 1000ull, (1ull << 40) + 7}) {
        BitWriter out;
        std::vector<std::uint64_t> xs;
        for (std::uint64_t x = 0; x < std::min<std::uint64_t>(n, 300); ++x) xs.push_back(x);
        xs.push_back(n - 1);
        xs.push_back(n / 2);
        std::size_t expected_bits = 0;
        for (auto x : xs) {
            write_centred_minimal_binary(out, x, n);
            expected_bits += centred_minimal_binary_length(x, n);
        }
        EXPECT_EQ(out.bit_count(), expected_bits);
        BitReader in(out.bytes(), "test");
        for (auto x : xs) EXPECT_EQ(read_centred_minimal_binary(in, n), x) << "n = " << n;
    }
}

TEST(SuffixArray, MatchesBruteForce) {
    std::mt19937 rng(7);
    for (int trial = 0; trial < 200; ++trial) {
        const unsigned alphabet = 1 + rng() % 9;
        const auto text = random_symbols(rng, rng() % 200, alphabet);
        ASSERT_EQ(suffix_array(text, alphabet), naive_suffix_array(text)) << "trial " << trial;
    }
    // Highly repetitive input (the worst case of prefix doubling).
    const std::vector<std::uint8_t> runs(5000, 8);
    EXPECT_EQ(suffix_array(runs, 9), naive_suffix_array(runs));
}

TEST(Bwt, KnownTransformAndRoundTrips) {
    // "banana" over a=0, b=1, n=2: rotations of banana$ sorted -> last column annb$aa.
    const std::vector<std::uint8_t> banana{1, 0, 2, 0, 2, 0};
    const BwtResult r = bwt_forward(banana, 3);
    EXPECT_EQ(r.last_column, (std::vector<std::uint8_t>{0, 2, 2, 1, 0, 0}));
    EXPECT_EQ(r.primary_index, 4u);
    EXPECT_EQ(bwt_inverse(r.last_column, r.primary_index, 3, "test"), banana);

    std::mt19937 rng(11);
    for (int trial = 0; trial < 300; ++trial) {
        const auto text = random_symbols(rng, rng() % 500, 9);
        const BwtResult t = bwt_forward(text, 9);
        ASSERT_EQ(bwt_inverse(t.last_column, t.primary_index, 9, "test"), text);
    }
    EXPECT_TRUE(bwt_inverse({}, 0, 9, "test").empty());
}

TEST(Bwt, BadPrimaryIndexIsRejected) {
    const std::vector<std::uint8_t> text{1, 1, 2, 0, 5, 8, 8, 7, 3, 3, 6};
    const BwtResult t = bwt_forward(text, 9);
    EXPECT_THROW(bwt_inverse(t.last_column, text.size() + 1, 9, "test"), Error);
    // Any other index either fails or gives a different text, never a crash.
    for (std::size_t p = 0; p <= text.size(); ++p) {
        if (p == t.primary_index) continue;
        try {
            EXPECT_NE(bwt_inverse(t.last_column, p, 9, "test"), text);
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        }
    }
}

TEST(Transforms, Mtf2KeepsTheFrontSymbolAfterOneInterruption) {
    // Worked by hand, table [0 1 2]: the lone 1 interrupting the run of 0 stays at position 1
    // (after a 0 it is not moved to the front), so the run of 0 continues as zeros; the 2 found
    // at position 2 goes to position 1 ([0 2 1]) and reaches the front when seen again after a
    // non-zero position ([2 0 1]).
    const std::vector<std::uint8_t> s{0, 0, 1, 0, 0, 2, 2, 2};
    const auto m = mtf_encode(s, 3, MtfRule::Mtf2);
    EXPECT_EQ(m, (std::vector<std::uint8_t>{0, 0, 1, 0, 0, 2, 1, 0}));
    EXPECT_EQ(mtf_encode(s, 3), (std::vector<std::uint8_t>{0, 0, 1, 1, 0, 2, 0, 0}));
    EXPECT_EQ(mtf_decode(m, 3, "test", MtfRule::Mtf2), s);
    // Round trip on random strings over the code alphabet.
    std::mt19937 random(7);
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<std::uint8_t> text(random() % 300);
        for (auto& c : text) c = static_cast<std::uint8_t>(random() % 3 == 0 ? random() % 9 : random() % 2);
        EXPECT_EQ(mtf_decode(mtf_encode(text, 9, MtfRule::Mtf2), 9, "test", MtfRule::Mtf2), text);
    }
    EXPECT_THROW(mtf_decode(std::vector<std::uint8_t>{9}, 9, "test", MtfRule::Mtf2), Error);
}

TEST(Transforms, MtfAndCumulativeSum) {
    const std::vector<std::uint8_t> s{8, 8, 8, 1, 1, 8, 0, 0, 0};
    const auto m = mtf_encode(s, 9);
    EXPECT_EQ(m, (std::vector<std::uint8_t>{8, 0, 0, 2, 0, 1, 2, 0, 0}));
    EXPECT_EQ(mtf_decode(m, 9, "test"), s);
    EXPECT_THROW(mtf_decode(std::vector<std::uint8_t>{9}, 9, "test"), Error);

    const std::vector<std::uint64_t> v{3, 0, 0, 8, 1};
    const auto q = cumulative_sum(v);
    EXPECT_EQ(q, (std::vector<std::uint64_t>{3, 3, 3, 11, 12}));
    EXPECT_EQ(differences(q, 8, "test"), v);
    EXPECT_THROW(differences(q, 7, "test"), Error);  // gap 8 over the bound
    EXPECT_THROW(differences(std::vector<std::uint64_t>{3, 2}, 8, "test"), Error);
}

// Strnad et al. 2020, §2.3: Q[1] = 18 and Q[45] = 106 bound the middle element Q[23] to [18, 106], which
// takes ceil(log2(89)) = 7 bits; then Q[12] takes ceil(log2(Q[23] - 18 + 1)) bits and Q[34]
// ceil(log2(106 - Q[23] + 1)) bits.
TEST(Interpolative, Section23WorkedExample) {
    const std::vector<std::uint64_t> q = section_2_3_sequence(57);
    std::vector<InterpolativeStep> trace;
    BitWriter out;
    write_interpolative_between(out, q, 0, 44, {.middle_code = MiddleCode::FixedBinary}, &trace);
    ASSERT_GE(trace.size(), 3u);
    EXPECT_EQ(trace[0].index, 22u);  // Q[23]
    EXPECT_EQ(trace[0].low, 18u);
    EXPECT_EQ(trace[0].high, 106u);
    EXPECT_EQ(trace[0].bits, 7u);
    EXPECT_EQ(trace[1].index, 11u);  // Q[12], left half first
    EXPECT_EQ(trace[1].high, q[22]);
    EXPECT_EQ(trace[1].bits, ceil_log2(q[22] - 18 + 1));
    const auto right = std::find_if(trace.begin(), trace.end(), [](const InterpolativeStep& s) { return s.index == 33; });
    ASSERT_NE(right, trace.end());  // Q[34]
    EXPECT_EQ(right->low, q[22]);
    EXPECT_EQ(right->bits, ceil_log2(106 - q[22] + 1));
    std::size_t total = 0;
    for (const auto& s : trace) total += s.bits;
    EXPECT_EQ(out.bit_count(), total);

    std::vector<std::uint64_t> decoded(45, 0);
    decoded.front() = 18;
    decoded.back() = 106;
    BitReader in(out.bytes(), "test");
    read_interpolative_between(in, decoded, 0, 44, {.middle_code = MiddleCode::FixedBinary});
    EXPECT_EQ(decoded, q);
}

TEST(Interpolative, CentredCodesAndTheGapBound) {
    // Centred minimal binary: a central Q[23] costs 6 bits, one at the edge of [18, 106] 7.
    for (auto [middle, bits] : {std::pair<std::uint64_t, unsigned>{62, 6}, {18, 7}, {106, 7}}) {
        std::vector<InterpolativeStep> trace;
        BitWriter out;
        write_interpolative_between(out, section_2_3_sequence(middle), 0, 44, {}, &trace);
        EXPECT_EQ(trace[0].bits, bits) << "Q[23] = " << middle;
    }
    // With a known maximum gap 2, Q[23] is confined to [106 - 22*2, 18 + 22*2] = [62, 62]: 0 bits.
    std::vector<std::uint64_t> q(45);
    for (std::size_t i = 0; i < 45; ++i) q[i] = 18 + 2 * i;
    std::vector<InterpolativeStep> trace;
    BitWriter out;
    write_interpolative_between(out, q, 0, 44, {.max_gap = 2}, &trace);
    EXPECT_EQ(trace[0].low, 62u);
    EXPECT_EQ(trace[0].high, 62u);
    EXPECT_EQ(out.bit_count(), 0u);
}

TEST(Interpolative, RandomSequencesRoundTrip) {
    std::mt19937 rng(3);
    for (int trial = 0; trial < 300; ++trial) {
        const std::size_t n = rng() % 400;
        const std::uint64_t max_gap = 1 + rng() % 20;
        std::vector<std::uint64_t> gaps(n);
        for (auto& g : gaps) g = (rng() % 3 == 0) ? rng() % (max_gap + 1) : 0;
        const auto q = cumulative_sum(gaps);
        for (InterpolativeOptions options : {InterpolativeOptions{}, InterpolativeOptions{.max_gap = max_gap},
                                             InterpolativeOptions{.max_gap = max_gap, .middle_code = MiddleCode::FixedBinary}}) {
            BitWriter out;
            write_interpolative(out, q, options);
            BitReader in(out.bytes(), "test");
            ASSERT_EQ(read_interpolative(in, n, options), q) << "trial " << trial;
        }
    }
}

TEST(Interpolative, TruncatedStreamsFailCleanly) {
    std::mt19937 rng(5);
    std::vector<std::uint64_t> gaps(2000);
    for (auto& g : gaps) g = rng() % 9;
    const auto q = cumulative_sum(gaps);
    BitWriter out;
    write_interpolative(out, q, {.max_gap = 8});
    const std::vector<std::uint8_t> bytes = out.take();
    for (std::size_t cut : {std::size_t{0}, std::size_t{1}, bytes.size() / 2, bytes.size() - 1}) {
        BitReader in(std::span<const std::uint8_t>(bytes).first(cut), "cut");
        EXPECT_THROW(read_interpolative(in, q.size(), {.max_gap = 8}), Error) << "cut at " << cut;
    }
}

TEST(RangeCoder, AdaptiveBitsRoundTripAndTruncationFails) {
    std::mt19937 rng(9);
    std::vector<int> bits(20000);
    for (auto& b : bits) b = (rng() % 10) < 2;  // skewed: compresses below one bit each
    RangeEncoder enc;
    std::array<BitModel, 4> models_e{};
    int ctx = 0;
    for (int b : bits) {
        enc.encode(models_e[ctx], b);
        ctx = ((ctx << 1) | b) & 3;
    }
    enc.encode_direct(0x2A5, 10);
    const auto bytes = enc.finish();
    EXPECT_LT(bytes.size(), bits.size() / 8);  // H(0.2) ~ 0.72 bit
    const std::string test_context = "test", cut_context = "cut";
    RangeDecoder dec(bytes, test_context);
    std::array<BitModel, 4> models_d{};
    ctx = 0;
    for (int b : bits) {
        ASSERT_EQ(dec.decode(models_d[ctx]), b != 0);
        ctx = ((ctx << 1) | b) & 3;
    }
    EXPECT_EQ(dec.decode_direct(10), 0x2A5u);
    EXPECT_TRUE(dec.at_end());  // consumed exactly what was written
    auto truncated_decode = [&] {
        RangeDecoder cut(std::span<const std::uint8_t>(bytes).first(bytes.size() / 2), cut_context);
        std::array<BitModel, 4> m{};
        for (std::size_t i = 0; i < bits.size(); ++i) cut.decode(m[0]);
    };
    EXPECT_THROW(truncated_decode(), Error);
}
