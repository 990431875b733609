// Corrupt codes and radius lists are rejected with a clear Error(InvalidInput), never a crash or
// a hang: four structural defects by name (a fork without its lateral branch, a tip
// closing more branches than are open, a missing final tip, a radius list of the wrong length), then random and mutated codes.
#include "core/error.hpp"
#include "encode/chain_code.hpp"
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"
#include "paper_trees.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <random>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

CodeGeometry unit_geometry() {
    CodeGeometry geometry;
    geometry.voxel_size = 0.1;
    return geometry;
}

// The message of the Error(InvalidInput) thrown when decoding; fails the test otherwise.
std::string decode_error(const std::string& symbols, const std::vector<int>& radii) {
    try {
        decode_tree(ChainCode{CodeKind::DBF6, symbols, radii}, unit_geometry(), "test code");
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput) << e.what();
        return e.what();
    }
    ADD_FAILURE() << "code '" << symbols << "' was accepted";
    return {};
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST(CorruptCode, UnknownSymbolIsNamedWithItsPosition) {
    const std::string message = decode_error("11189117", {1, 2});
    EXPECT_TRUE(contains(message, "test code")) << message;
    EXPECT_TRUE(contains(message, "unknown chain code symbol '9' at character 5")) << message;
    EXPECT_TRUE(contains(decode_error("111x7", {1}), "'x'"));
    EXPECT_TRUE(contains(decode_error("11 17", {1}), "' '"));
}

TEST(CorruptCode, MissingFinalTipIsRejected) {
    EXPECT_TRUE(contains(decode_error("1118111", {1, 2}), "without the final branch tip 7"));
    EXPECT_TRUE(contains(decode_error("1118", {1}), "without the final branch tip 7"));
    EXPECT_TRUE(contains(decode_error("", {}), "empty chain code"));
}

TEST(CorruptCode, RadiusListOfTheWrongLengthIsRejected) {
    const std::string too_few = decode_error(test::kFig4DBF6, {10, 9, 6});
    EXPECT_TRUE(contains(too_few, "radius list has 3 values but the DBF6 code has 8 internodes")) << too_few;
    EXPECT_TRUE(contains(decode_error("1117", {1, 2}), "radius list has 2 values"));
    EXPECT_TRUE(contains(decode_error("1117", {-1}), "negative"));
}

TEST(CorruptCode, ForkWithoutALateralIsRejected) {
    EXPECT_TRUE(contains(decode_error("11161117", {1, 2}), "1 fork(s) 6 without a lateral branch"));
    EXPECT_TRUE(contains(decode_error("1117117", {1, 2}), "tip symbol 7 at character 4 ends the last open branch"));
}

TEST(CorruptCode, LodRejectsTheSameDefects) {
    EXPECT_THROW(reduce_lod(ChainCode{CodeKind::DBF6, "11161117", {1, 2}}, 1.0), Error);
    EXPECT_THROW(reduce_lod(ChainCode{CodeKind::DBF6, "1117", {1, 2}}, 1.0), Error);
    EXPECT_THROW(reduce_lod(ChainCode{CodeKind::DBF6, "1a17", {1}}, 1.0), Error);
    EXPECT_THROW(reduce_lod(ChainCode{CodeKind::DBF6, "111", {}}, 1.0), Error);
}

TEST(CorruptCode, HugeDifferentialMovesAreRejectedNotOverflowed) {
    // DBF6 corrections accumulate: 40 internodes each adding 2^35 moves would be far beyond 2^40.
    // Build the equivalent with a long single correction repeated through the chain.
    std::string symbols(std::size_t{1} << 21, '0');  // one internode of 2^21 moves
    symbols += '8';
    std::vector<int> radii{1};
    for (int k = 0; k < 600000; ++k) {  // each 8 repeats the move: position grows to ~1.3e12 voxels
        symbols += '8';
        radii.push_back(1);
    }
    symbols.back() = '7';
    const std::string message = decode_error(symbols, radii);
    EXPECT_TRUE(contains(message, "2^40")) << message;
}

TEST(CorruptCode, RandomCodesNeverCrash) {
    std::mt19937 engine(20240601u);
    const std::string alphabet = "0123456788667779a";
    int accepted = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const std::size_t length = engine() % 40;
        std::string symbols;
        for (std::size_t i = 0; i < length; ++i) symbols += alphabet[engine() % alphabet.size()];
        const auto terminators = static_cast<std::size_t>(
                std::count_if(symbols.begin(), symbols.end(), [](char c) { return c == '6' || c == '7' || c == '8'; }));
        // Mostly the right number of radii, sometimes one off.
        const std::size_t count = engine() % 4 == 0 ? terminators + 1 : terminators;
        std::vector<int> radii(count);
        for (int& r : radii) r = static_cast<int>(engine() % 20);
        const ChainCode code{engine() % 2 ? CodeKind::F6 : CodeKind::DBF6, symbols, radii};
        try {
            const TreeGraph tree = decode_tree(code, unit_geometry());
            tree.validate("decoded");
            EXPECT_LE(tree.size(), terminators + 1);
            const ChainCode reduced = reduce_lod(code, static_cast<double>(engine() % 20));
            EXPECT_LE(reduced.symbols.size(), symbols.size());
            decode_tree(reduced, unit_geometry());  // LOD output of a valid code decodes
            ++accepted;
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput) << symbols << ": " << e.what();
        }
    }
    EXPECT_GT(accepted, 100);  // the generator does produce valid codes, so both paths are exercised
}

TEST(CorruptCode, MutatedPaperCodesAreDecodedOrRejected) {
    const std::string base = test::kFig4DBF6;
    const std::vector<int> radii{10, 9, 6, 3, 4, 3, 2, 1};
    for (std::size_t i = 0; i < base.size(); ++i) {
        for (char replacement = '0'; replacement <= '9'; ++replacement) {
            for (const std::string& mutated : {base.substr(0, i) + replacement + base.substr(i + 1), base.substr(0, i) + base.substr(i + 1),
                                               base.substr(0, i) + replacement + base.substr(i)}) {
                try {
                    const TreeGraph tree = decode_tree(ChainCode{CodeKind::DBF6, mutated, radii}, unit_geometry());
                    tree.validate("decoded");
                } catch (const Error& e) {
                    EXPECT_EQ(e.code(), ExitCode::InvalidInput);
                }
            }
        }
    }
}

namespace {

// The internode form of a symbol string made of moves and terminators only (no check).
InternodeVectors internode_form(const ChainCode& code) {
    InternodeVectors out;
    out.kind = code.kind;
    out.radii = code.radii;
    Voxel delta = Voxel::Zero();
    for (const char c : code.symbols) {
        if (c < kFork) {
            delta[(c - '0') % 3] += c < '3' ? 1 : -1;
            continue;
        }
        out.vectors.push_back(delta);
        out.terminators.push_back(c);
        delta.setZero();
    }
    return out;
}

bool same_tree(const TreeGraph& a, const TreeGraph& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (a.nodes[i].position != b.nodes[i].position || a.nodes[i].radius != b.nodes[i].radius ||
            a.nodes[i].parent != b.nodes[i].parent || a.nodes[i].children != b.nodes[i].children)
            return false;
    return true;
}

}  // namespace

// The forest decoder builds skeletons from internodes, never from symbol text: it must accept
// exactly the codes decode_tree accepts, build the same trees, and reject the rest cleanly.
TEST(CorruptCode, InternodeFormDecodesAndRejectsLikeTheText) {
    std::mt19937 engine(77);
    const std::string alphabet = "01234588667778";
    int accepted = 0, rejected = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        std::string symbols;
        for (std::size_t i = 0, length = engine() % 40; i < length; ++i) symbols += alphabet[engine() % alphabet.size()];
        if (!symbols.empty() && symbols.back() < kFork) symbols += kTip;  // the internode form has no trailing moves
        const auto terminators = static_cast<std::size_t>(std::count_if(symbols.begin(), symbols.end(), [](char c) { return c >= kFork; }));
        std::vector<int> radii(engine() % 8 == 0 ? terminators + 1 : terminators);
        for (int& r : radii) r = static_cast<int>(engine() % 20) - (engine() % 50 == 0 ? 25 : 0);
        const ChainCode code{engine() % 2 ? CodeKind::F6 : CodeKind::DBF6, symbols, radii};
        std::optional<TreeGraph> from_text;
        try {
            from_text = decode_tree(code, unit_geometry());
        } catch (const Error&) {}
        try {
            const TreeGraph from_internodes = decode_internodes(internode_form(code), unit_geometry());
            ASSERT_TRUE(from_text) << symbols << ": accepted only in internode form";
            EXPECT_TRUE(same_tree(*from_text, from_internodes)) << symbols;
            ++accepted;
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput) << e.what();
            EXPECT_FALSE(from_text) << symbols << ": rejected only in internode form: " << e.what();
            ++rejected;
        }
    }
    EXPECT_GT(accepted, 100);
    EXPECT_GT(rejected, 100);
    // The structural defects, named.
    auto error_of = [](const std::string& symbols, const std::vector<int>& radii) -> std::string {
        try {
            decode_internodes(internode_form(ChainCode{CodeKind::DBF6, symbols, radii}), unit_geometry(), "internodes");
        } catch (const Error& e) {
            return e.what();
        }
        return "accepted";
    };
    EXPECT_TRUE(contains(error_of("11161117", {1, 2}), "1 fork(s) 6 without a lateral branch"));
    EXPECT_TRUE(contains(error_of("1117117", {1, 2}), "tip 7 of internode 1 ends the last open branch"));
    EXPECT_TRUE(contains(error_of("1118", {1}), "without the final branch tip 7"));
    EXPECT_TRUE(contains(error_of("1117", {1, 2}), "radius list has 2 values"));
}
