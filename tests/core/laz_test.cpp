// LAZ decoding without real data: the arithmetic decoder and integer decompressor on hand-made
// streams whose results follow from the update rules by hand, the LASzip VLR checks, and
// malformed chunks and files built byte by byte (each must give one Error, never a crash).
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/laz_chunk.hpp"
#include "core/laz_codec.hpp"
#include "core/little_endian.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

using namespace treelobes;
using namespace treelobes::laz;
using treelobes::test::error_code_of;

namespace {

using Bytes = std::vector<std::uint8_t>;

std::string message_of(const std::function<void()>& action) {
    try {
        action();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

}  // namespace

// Raw bits: the interval is split evenly, so 8 bits read back the leading bytes. After the first
// read the remainder 0x12345678 - 0x12 * 0xFFFFFF = 0x34568A shifts in the next byte, and
// 0x34568A9A / 0xFFFFFF = 0x34.
TEST(LazCodec, RawBitsReadBackTheLeadingBytes) {
    const Bytes stream = {0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC};
    ArithmeticDecoder decoder;
    decoder.init(stream.data(), stream.size());
    EXPECT_EQ(decoder.read_bits(8), 0x12u);
    EXPECT_EQ(decoder.read_bits(8), 0x34u);
    EXPECT_EQ(decoder.overrun(), 0u);
}

// A fresh binary model gives 0 probability 1/2: the threshold is 4096 * (2^32 - 1 >> 13) =
// 0x7FFFF000, so values below it decode 0 and values above decode 1.
TEST(LazCodec, FreshBitModelSplitsAtHalf) {
    for (const auto& [first, expected] : {std::pair<std::uint8_t, std::uint32_t>{0x12, 0}, {0x7F, 0}, {0x80, 1}, {0xF0, 1}}) {
        const Bytes stream = {first, 0, 0, 0};
        ArithmeticDecoder decoder;
        decoder.init(stream.data(), stream.size());
        BitModel model;
        EXPECT_EQ(decoder.decode_bit(model), expected) << int(first);
    }
}

// A fresh 4-symbol model is uniform: symbol k covers [k, k + 1) * (0x1FFFF * 8192).
TEST(LazCodec, FreshSymbolModelIsUniform) {
    for (const auto& [first, expected] : {std::pair<std::uint8_t, std::uint32_t>{0x00, 0}, {0x50, 1}, {0x90, 2}, {0xC0, 3}}) {
        const Bytes stream = {first, 0, 0, 0};
        ArithmeticDecoder decoder;
        decoder.init(stream.data(), stream.size());
        SymbolModel model(4);
        EXPECT_EQ(decoder.decode_symbol(model), expected) << int(first);
    }
}

// Large models use the lookup table; on a uniform model the table and the bisection agree:
// the top byte b of the code value selects symbol floor(b * 256 / 256) = b for 256 symbols.
TEST(LazCodec, TableLookupAgreesWithUniformSplit) {
    for (int b : {0, 1, 77, 128, 254, 255}) {
        const Bytes stream = {static_cast<std::uint8_t>(b), 0x80, 0, 0};
        ArithmeticDecoder decoder;
        decoder.init(stream.data(), stream.size());
        SymbolModel model(256);
        EXPECT_EQ(decoder.decode_symbol(model), static_cast<std::uint32_t>(b));
    }
}

// An all-zero stream codes bit-length class 0 and corrector bit 0: every value equals its
// prediction, including negative and extreme 32-bit ones.
TEST(LazCodec, ZeroStreamDecompressesToThePrediction) {
    const Bytes stream(64, 0);
    ArithmeticDecoder decoder;
    decoder.init(stream.data(), stream.size());
    IntegerDecompressor ic(decoder, 32, 2);
    for (std::int32_t pred : {0, 1234, -5678, INT32_MAX, INT32_MIN}) {
        EXPECT_EQ(ic.decompress(pred, 1), pred);
        EXPECT_EQ(ic.k(), 0u);
    }
}

TEST(LazCodec, ReadingPastTheEndIsCountedNotPerformed) {
    const Bytes stream = {0xAB, 0xCD};
    ArithmeticDecoder decoder;
    decoder.init(stream.data(), stream.size());
    EXPECT_EQ(decoder.overrun(), 2u);  // priming needs four bytes
    decoder.read_int();
    EXPECT_GT(decoder.overrun(), 2u);
}

// Random bytes through every model kind: decoding garbage must stay inside the tables.
TEST(LazCodec, GarbageNeverLeavesTheTables) {
    std::mt19937 rng(7);
    Bytes stream(4096);
    for (auto& b : stream) b = static_cast<std::uint8_t>(rng());
    ArithmeticDecoder decoder;
    decoder.init(stream.data(), stream.size());
    SymbolModel small(5), large(516);
    BitModel bit;
    IntegerDecompressor ic(decoder, 32, 9), ic16(decoder, 16, 4);
    for (int i = 0; i < 20000; ++i) {
        EXPECT_LT(decoder.decode_symbol(small), 5u);
        EXPECT_LT(decoder.decode_symbol(large), 516u);
        decoder.decode_bit(bit);
        ic.decompress(i, static_cast<std::uint32_t>(i % 9));
        const std::int32_t v = ic16.decompress(i & 0xFFFF, static_cast<std::uint32_t>(i % 4));
        EXPECT_GE(v, 0);
        EXPECT_LT(v, 65536);
    }
}

// ---------------------------------------------------------------------------------------------
// LASzip VLR

namespace {

Bytes laszip_vlr(std::uint16_t compressor, std::uint32_t chunk_size, const std::vector<Item>& items) {
    Bytes v(34 + 6 * items.size(), 0);
    store<std::uint16_t>(v.data(), compressor);
    v[4] = 3;
    v[5] = 4;
    store<std::uint32_t>(v.data() + 12, chunk_size);
    store<std::uint16_t>(v.data() + 32, static_cast<std::uint16_t>(items.size()));
    for (std::size_t i = 0; i < items.size(); ++i) {
        store<std::uint16_t>(v.data() + 34 + 6 * i, static_cast<std::uint16_t>(items[i].type));
        store<std::uint16_t>(v.data() + 36 + 6 * i, items[i].size);
        store<std::uint16_t>(v.data() + 38 + 6 * i, items[i].version);
    }
    return v;
}

const Item kPoint10{ItemType::Point10, 20, 2}, kGps{ItemType::GpsTime11, 8, 2}, kRgb{ItemType::Rgb12, 6, 2};

}  // namespace

TEST(LaszipVlr, AcceptsTheItemsOfItsPointFormat) {
    const LaszipVlr vlr = parse_laszip_vlr(laszip_vlr(2, 50000, {kPoint10, kGps, kRgb, {ItemType::Byte, 3, 2}}), 3, 37, "f.laz");
    EXPECT_EQ(vlr.chunk_size, 50000u);
    EXPECT_EQ(vlr.items.size(), 4u);
    const LaszipVlr layered =
            parse_laszip_vlr(laszip_vlr(3, kVariableChunkSize, {{ItemType::Point14, 30, 3}, {ItemType::Rgb14, 6, 3}}), 7, 36, "f.laz");
    EXPECT_TRUE(layered.variable_chunks());
}

TEST(LaszipVlr, RejectsItemsThatContradictTheHeader) {
    // RGB items for point format 1 (GPS time, no colour).
    EXPECT_NE(message_of([] {
                  parse_laszip_vlr(laszip_vlr(2, 50000, {kPoint10, kRgb}), 1, 26, "f.laz");
              }).find("do not match point format 1"),
              std::string::npos);
    // Items summing to 28 bytes for a 30-byte record.
    EXPECT_NE(message_of([] {
                  parse_laszip_vlr(laszip_vlr(2, 50000, {kPoint10, kGps}), 1, 30, "f.laz");
              }).find("point record length is 30"),
              std::string::npos);
    // Point-wise items for a LAS 1.4 format.
    EXPECT_EQ(error_code_of([] { parse_laszip_vlr(laszip_vlr(2, 50000, {kPoint10}), 6, 20, "f.laz"); }), ExitCode::InvalidInput);
    // LASzip 1.x item versions.
    EXPECT_NE(message_of([] {
                  parse_laszip_vlr(laszip_vlr(2, 50000, {{ItemType::Point10, 20, 1}}), 0, 20, "f.laz");
              }).find("only version 2"),
              std::string::npos);
    // Truncated VLR payloads.
    Bytes cut = laszip_vlr(2, 50000, {kPoint10, kGps});
    cut.resize(38);
    EXPECT_EQ(error_code_of([&] { parse_laszip_vlr(cut, 1, 28, "f.laz"); }), ExitCode::InvalidInput);
    EXPECT_EQ(error_code_of([] { parse_laszip_vlr(Bytes(10, 0), 0, 20, "f.laz"); }), ExitCode::InvalidInput);
}

// ---------------------------------------------------------------------------------------------
// Chunks

TEST(LazChunk, SinglePointChunkIsTheRawPoint) {
    const LaszipVlr vlr = parse_laszip_vlr(laszip_vlr(2, 50000, {kPoint10}), 0, 20, "f.laz");
    Bytes raw(20);
    for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = static_cast<std::uint8_t>(3 * i + 1);
    Bytes out(20, 0);
    decode_chunk(vlr, 20, raw, 1, out.data(), LayerSelection::all(), "f.laz", 0);
    EXPECT_EQ(out, raw);
}

TEST(LazChunk, TooFewBytesForItsPointsIsAnError) {
    const LaszipVlr vlr = parse_laszip_vlr(laszip_vlr(2, 50000, {kPoint10, kGps}), 1, 28, "f.laz");
    Bytes chunk(28 + 6, 0x5A);  // a raw point and six bytes of stream for 10,000 points
    Bytes out(28 * 10000);
    const std::string message = message_of([&] { decode_chunk(vlr, 28, chunk, 10000, out.data(), LayerSelection::all(), "f.laz", 3); });
    EXPECT_NE(message.find("f.laz: LAZ chunk 3"), std::string::npos) << message;
    // Shorter than the raw first point.
    EXPECT_EQ(error_code_of([&] { decode_chunk(vlr, 28, Bytes(10, 0), 2, out.data(), LayerSelection::all(), "f.laz", 0); }),
              ExitCode::InvalidInput);
}

TEST(LazChunk, LayerSizesBeyondTheChunkAreAnError) {
    const LaszipVlr vlr = parse_laszip_vlr(laszip_vlr(3, kVariableChunkSize, {{ItemType::Point14, 30, 3}}), 6, 30, "f.laz");
    Bytes chunk(30 + 4 + 9 * 4, 0);
    store<std::uint32_t>(chunk.data() + 30, 5);
    store<std::uint32_t>(chunk.data() + 34, 1000);  // XY layer of 1000 bytes in a 70-byte chunk
    Bytes out(30 * 5);
    const std::string message = message_of([&] { decode_chunk(vlr, 30, chunk, 5, out.data(), LayerSelection::all(), "f.laz", 0); });
    EXPECT_NE(message.find("layer 1 declares 1000 bytes"), std::string::npos) << message;
    // A chunk that ends inside its layer table.
    chunk.resize(40);
    EXPECT_EQ(error_code_of([&] { decode_chunk(vlr, 30, chunk, 5, out.data(), LayerSelection::all(), "f.laz", 0); }),
              ExitCode::InvalidInput);
}

// ---------------------------------------------------------------------------------------------
// Whole files built byte by byte

namespace {

// A LAS 1.2 header with point format 0 marked LAZ, a LASzip VLR and `tail` after it (the
// chunk-table offset and the chunks).
Bytes laz_file(std::uint32_t points, const Bytes& tail) {
    const Bytes vlr = laszip_vlr(2, 50000, {kPoint10});
    Bytes f(227, 0);
    std::memcpy(f.data(), "LASF", 4);
    f[24] = 1;
    f[25] = 2;
    store<std::uint16_t>(f.data() + 94, 227);
    store<std::uint32_t>(f.data() + 96, static_cast<std::uint32_t>(227 + 54 + vlr.size()));
    store<std::uint32_t>(f.data() + 100, 1);
    f[104] = 0x80;
    store<std::uint16_t>(f.data() + 105, 20);
    store<std::uint32_t>(f.data() + 107, points);
    for (int k = 0; k < 3; ++k) store<double>(f.data() + 131 + 8 * k, 0.01);
    Bytes header(54, 0);
    std::memcpy(header.data() + 2, "laszip encoded", 14);
    store<std::uint16_t>(header.data() + 18, 22204);
    store<std::uint16_t>(header.data() + 20, static_cast<std::uint16_t>(vlr.size()));
    f.insert(f.end(), header.begin(), header.end());
    f.insert(f.end(), vlr.begin(), vlr.end());
    f.insert(f.end(), tail.begin(), tail.end());
    return f;
}

Bytes le64(std::uint64_t v) {
    Bytes b(8);
    store<std::uint64_t>(b.data(), v);
    return b;
}

}  // namespace

TEST(LazFile, ChunkTableOutsideTheFileIsAnError) {
    const Bytes file = laz_file(10, le64(1'000'000));
    const std::string message = message_of([&] { read_las_buffer(file, "bad.laz"); });
    EXPECT_NE(message.find("bad.laz: LAZ chunk table offset 1000000 lies outside the file"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
}

TEST(LazFile, ChunkTableClaimingMoreChunksThanFitIsAnError) {
    // Offset pointing at a table right after 20 bytes of chunk data, declaring 1000 chunks.
    const std::size_t data_start = laz_file(10, {}).size() + 8;
    // The chunk table offset (8 bytes), 20 bytes of chunk data, then the table: version, count.
    Bytes tail(8 + 20 + 8, 0);
    store<std::uint64_t>(tail.data(), data_start + 20);
    store<std::uint32_t>(tail.data() + 8 + 20 + 4, 1000);
    const std::string message = message_of([&] { read_las_buffer(laz_file(10, tail), "bad.laz"); });
    EXPECT_NE(message.find("declares 1000 chunks"), std::string::npos) << message;
}

TEST(LazFile, MissingLaszipVlrAndTruncationAreErrors) {
    Bytes file = laz_file(10, le64(0));
    store<std::uint32_t>(file.data() + 100, 0);  // no VLR declared
    EXPECT_NE(message_of([&] { read_las_buffer(file, "x.laz"); }).find("no LASzip VLR"), std::string::npos);
    const Bytes whole = laz_file(10, le64(0));
    for (std::size_t cut : {std::size_t{0}, std::size_t{100}, whole.size() - 4, whole.size() - 1}) {
        const Bytes truncated(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(cut));
        EXPECT_EQ(error_code_of([&] { read_las_buffer(truncated, "x.laz"); }), ExitCode::InvalidInput) << cut;
    }
}
