// The two coders of chain codes and radii (Strnad et al. 2020, §3.3 and `best`): exact round trips on
// 1,000 random trees at every LOD, non-monotone radii, arbitrary symbol strings, the §3.3 radii
// transform on a hand-checked example, and clean errors for damaged streams.
#include "core/error.hpp"
#include "encode/coder.hpp"
#include "encode/coder_best.hpp"
#include "encode/bitstream.hpp"
#include "encode/coder_ic.hpp"
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"
#include "paper_trees.hpp"
#include "random_tree.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

test::RandomTreeProfile profile_for(std::uint32_t seed) {
    test::TreeRandom random(seed * 2654435761u + 5u);
    test::RandomTreeProfile p;
    p.max_nodes = 10 + random.below(400);
    p.max_laterals = random.uniform() < 0.5 ? 1 : 2 + random.below(3);
    p.wiggle_degrees = random.uniform() < 0.3 ? 0.0 : random.uniform(2.0, 25.0);
    p.fork_probability = random.uniform(0.1, 0.5);
    p.root_stems = random.uniform() < 0.8 ? 1 : 2 + random.below(3);
    p.trunk_internodes = 5 + random.below(30);
    return p;
}

void expect_round_trip(const ChainCode& code, Coder coder, const std::string& what) {
    const CodedStreams streams = encode_streams(code, coder);
    const ChainCode decoded = decode_streams(streams.symbols, streams.radii, coder, code.kind);
    ASSERT_EQ(decoded.symbols, code.symbols) << what << " (" << coder_name(coder) << ")";
    ASSERT_EQ(decoded.radii, code.radii) << what << " (" << coder_name(coder) << ")";
    // Deterministic: coding again gives the same bytes.
    const CodedStreams again = encode_streams(code, coder);
    ASSERT_EQ(again.symbols, streams.symbols);
    ASSERT_EQ(again.radii, streams.radii);
}

}  // namespace

TEST(Coders, ExactRoundTripOnAThousandRandomTreesAtEveryLod) {
    std::size_t total_internodes = 0;
    for (std::uint32_t seed = 1; seed <= 1000; ++seed) {
        const TreeGraph tree = test::random_tree(profile_for(seed), seed);
        EncodeOptions options;
        options.resolution = seed % 3 == 0 ? 3.0 : (seed % 3 == 1 ? 5.0 : 10.0);
        options.internode_length = 0.1;
        options.kind = seed % 4 == 0 ? CodeKind::F6 : CodeKind::DBF6;
        const EncodedTree encoded = encode_tree(tree, options);
        const std::vector<ChainCode> lods = lod_chain(encoded.code, lod_thresholds(encoded.code.radii, 4));
        for (std::size_t k = 0; k < lods.size(); ++k) {
            const std::string what = "seed " + std::to_string(seed) + " LOD " + std::to_string(k);
            expect_round_trip(lods[k], Coder::Interpolative, what);
            expect_round_trip(lods[k], Coder::Best, what);
            if (HasFatalFailure()) return;
        }
        total_internodes += encoded.code.radii.size();
    }
    EXPECT_GT(total_internodes, 90000u);
}

TEST(Coders, NonMonotoneRadiiAndExtremeValuesRoundTrip) {
    const TreeGraph tree = test::random_tree(profile_for(77), 77);
    EncodeOptions options;
    options.internode_length = 0.1;
    ChainCode code = encode_tree(tree, options).code;
    std::mt19937 rng(4);
    for (int& r : code.radii) r = static_cast<int>(rng() % 50);  // no order at all
    expect_round_trip(code, Coder::Interpolative, "random radii");
    expect_round_trip(code, Coder::Best, "random radii");
    code.radii.front() = 2000000000;
    code.radii.back() = 0;
    expect_round_trip(code, Coder::Interpolative, "huge radius");
    expect_round_trip(code, Coder::Best, "huge radius");
    for (int& r : code.radii) r = 7;  // constant
    expect_round_trip(code, Coder::Interpolative, "constant radii");
    expect_round_trip(code, Coder::Best, "constant radii");
}

TEST(Coders, AnySymbolStringRoundTrips) {
    // Not a valid tree code, and not canonical internodes: `best` falls back to its generic model.
    std::mt19937 rng(8);
    for (int trial = 0; trial < 50; ++trial) {
        ChainCode code;
        const std::size_t n = rng() % 300;
        for (std::size_t i = 0; i < n; ++i) code.symbols += static_cast<char>('0' + rng() % 9);
        for (char c : code.symbols)
            if (c >= '6') code.radii.push_back(static_cast<int>(rng() % 100));
        expect_round_trip(code, Coder::Interpolative, "trial " + std::to_string(trial));
        expect_round_trip(code, Coder::Best, "trial " + std::to_string(trial));
    }
    expect_round_trip(ChainCode{}, Coder::Interpolative, "empty");
    expect_round_trip(ChainCode{}, Coder::Best, "empty");
}

TEST(Coders, InvalidInputIsRejectedBeforeCoding) {
    ChainCode code;
    code.symbols = "0018";
    code.radii = {1, 2};  // one internode, two radii
    EXPECT_THROW(encode_streams(code, Coder::Best), Error);
    code.symbols = "009";
    code.radii = {};
    EXPECT_THROW(encode_streams(code, Coder::Interpolative), Error);
    EXPECT_EQ(parse_coder("ic"), Coder::Interpolative);
    EXPECT_EQ(parse_coder("best"), Coder::Best);
    EXPECT_THROW(parse_coder("gzip"), Error);
}

// §3.3 on the radii of Fig. 6 (R = 10,9,6,3 | 4,3 | 2 | 1; branches end at each 7): zero-aligned
// by the smallest radius 1 -> 9,8,5,2 | 3,2 | 1 | 0; inverted sublists 2,5,8,9 | 2,3 | 1 | 0 ->
// d-gaps 2,3,3,1 | 2,1 | 1 | 0 -> cumulative sum 2,5,8,9,11,12,13,13.
// The interpolative coder stores a run of equal values in no bits, so a few bytes can claim any
// symbol count: found by fuzz/forest_fuzz.cpp in CI, a record decoding for 19 s under ASan. Counts
// above kMaxCodeSymbols are refused before anything is allocated.
TEST(IcCoder, ASymbolCountAboveTheLimitIsRefusedBeforeDecoding) {
    BitWriter out;
    write_count(out, kMaxCodeSymbols + 1);
    for (int i = 0; i < 64; ++i) out.write_bit(false);
    const std::vector<std::uint8_t> bytes = out.take();
    try {
        ic_decode_symbols(bytes, "record");
        FAIL() << "a code longer than the limit was decoded";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("exceeds the decoder limit"), std::string::npos) << e.what();
    }
}

TEST(IcCoder, RadiiTransformOfFig6) {
    const std::string symbols = test::kFig4DBF6;
    const std::vector<int> radii{10, 9, 6, 3, 4, 3, 2, 1};
    ASSERT_EQ(count_symbols(symbols).internodes, radii.size());
    ASSERT_EQ(count_symbols(symbols).tips, 4u);
    const RadiiSequence q = radii_to_sequence(symbols, radii, GapMap::Shift);
    EXPECT_EQ(q.offset, 1);
    EXPECT_EQ(q.shift, 0u);
    const std::vector<std::int64_t> gaps = radius_gaps(symbols, radii, 1);
    EXPECT_EQ(gaps, (std::vector<std::int64_t>{2, 3, 3, 1, 2, 1, 1, 0}));
    EXPECT_EQ(q.cumulative, (std::vector<std::uint64_t>{2, 5, 8, 9, 11, 12, 13, 13}));
}

TEST(IcCoder, NegativeGapsAreMappedLosslessly) {
    const std::string symbols = "0870007";  // a branch of two internodes, then one of one
    const std::vector<int> radii{2, 5, 9};  // the first branch thickens toward its tip
    ASSERT_EQ(count_symbols(symbols).internodes, 3u);
    const RadiiSequence shifted = radii_to_sequence(symbols, radii, GapMap::Shift);
    EXPECT_EQ(shifted.offset, 2);
    EXPECT_EQ(radius_gaps(symbols, radii, 2), (std::vector<std::int64_t>{3, -3, 7}));
    EXPECT_EQ(shifted.shift, 3u);
    EXPECT_EQ(shifted.cumulative, (std::vector<std::uint64_t>{6, 6, 16}));
    const RadiiSequence zigzagged = radii_to_sequence(symbols, radii, GapMap::ZigZag);
    EXPECT_EQ(zigzagged.cumulative, (std::vector<std::uint64_t>{6, 11, 25}));
    const auto bytes = ic_encode_radii(symbols, radii);
    EXPECT_EQ(ic_decode_radii(bytes, symbols, "test"), radii);
}

TEST(Coders, DamagedStreamsFailCleanly) {
    const TreeGraph tree = test::random_tree(profile_for(5), 5);
    EncodeOptions options;
    options.internode_length = 0.1;
    const ChainCode code = encode_tree(tree, options).code;
    std::mt19937 rng(21);
    for (Coder coder : {Coder::Interpolative, Coder::Best}) {
        const CodedStreams streams = encode_streams(code, coder);
        // Truncation at every length: an error or (rarely, for a cut in the padding) the code.
        for (std::size_t cut = 0; cut < streams.symbols.size(); ++cut) {
            try {
                const ChainCode d = decode_streams(std::span(streams.symbols).first(cut), streams.radii, coder, code.kind);
                EXPECT_EQ(d.symbols, code.symbols) << "cut " << cut;
            } catch (const Error& e) {
                EXPECT_EQ(e.code(), ExitCode::InvalidInput);
            }
        }
        for (std::size_t cut = 0; cut < streams.radii.size(); ++cut) {
            try {
                decode_streams(streams.symbols, std::span(streams.radii).first(cut), coder, code.kind);
                ADD_FAILURE() << coder_name(coder) << " radii cut at " << cut << " decoded";
            } catch (const Error& e) {
                EXPECT_EQ(e.code(), ExitCode::InvalidInput);
            }
        }
        // Random bit flips: never a crash or a hang (the container's CRC catches what decodes).
        for (int trial = 0; trial < 300; ++trial) {
            CodedStreams damaged = streams;
            auto& target = trial % 2 ? damaged.symbols : damaged.radii;
            if (target.empty()) continue;
            target[rng() % target.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
            try {
                decode_streams(damaged.symbols, damaged.radii, coder, code.kind);
            } catch (const Error& e) {
                EXPECT_EQ(e.code(), ExitCode::InvalidInput);
            }
        }
    }
}

TEST(BestPrior, TrainedPriorRoundTripsAndIsRequiredToDecode) {
    std::vector<ChainCode> codes;
    for (std::uint32_t seed = 200; seed < 230; ++seed) {
        EncodeOptions options;
        options.internode_length = 0.1;
        codes.push_back(encode_tree(test::random_tree(profile_for(seed), seed), options).code);
    }
    std::vector<const ChainCode*> pointers;
    for (const ChainCode& c : codes) pointers.push_back(&c);
    const BestPrior prior = BestPrior::train(pointers);
    const std::vector<std::uint8_t> bytes = prior.serialize();
    EXPECT_EQ(BestPrior::deserialize(bytes, "prior").serialize(), bytes);  // the stored form is a fixed point
    EXPECT_EQ(BestPrior::train(pointers).serialize(), bytes);              // deterministic
    std::size_t with_prior = 0, without = 0;
    for (const ChainCode& code : codes) {
        const CodedStreams primed = encode_streams(code, Coder::Best, "test", &prior);
        const ChainCode decoded = decode_streams(primed.symbols, primed.radii, Coder::Best, code.kind, "test", &prior);
        ASSERT_EQ(decoded.symbols, code.symbols);
        ASSERT_EQ(decoded.radii, code.radii);
        with_prior += primed.symbols.size() + primed.radii.size();
        const CodedStreams plain = encode_streams(code, Coder::Best);
        without += plain.symbols.size() + plain.radii.size();
    }
    EXPECT_LT(with_prior, without);  // the trees it was trained on code smaller
    std::vector<std::uint8_t> damaged = bytes;
    damaged.resize(bytes.size() - 3);
    EXPECT_THROW(BestPrior::deserialize(damaged, "prior"), Error);
}
