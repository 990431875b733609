// Animated PNG: the chunk stream read back by an independent parser (CRC-32 computed here, not by
// zlib), frames decoded again from their IDAT/fdAT data, and `render --view orbit` end to end.
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "render/apng.hpp"
#include "render/image.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

using namespace treelobes;
using namespace treelobes::render;

namespace {

std::uint32_t crc32_of(const std::string& bytes) {  // PNG spec Annex D, bit by bit
    std::uint32_t crc = 0xffffffffu;
    for (unsigned char byte : bytes) {
        crc ^= byte;
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return crc ^ 0xffffffffu;
}

std::uint32_t u32(const std::string& s, std::size_t at) {
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(s[at + k]);
    return v;
}

std::string be32(std::uint32_t v) {
    std::string s;
    for (int shift = 24; shift >= 0; shift -= 8) s.push_back(static_cast<char>((v >> shift) & 0xff));
    return s;
}

std::string chunk(const std::string& type, const std::string& data) {
    return be32(static_cast<std::uint32_t>(data.size())) + type + data + be32(crc32_of(type + data));
}

struct Apng {
    std::vector<std::string> chunk_types;
    std::uint32_t declared_frames = 0, plays = 99;
    std::vector<std::uint32_t> sequence;                               // fcTL and fdAT sequence numbers in file order
    std::vector<Image> frames;                                         // decoded
    std::vector<std::pair<std::uint32_t, std::uint32_t>> frame_sizes;  // from fcTL
};

// Parses an APNG, checking every CRC; each frame is decoded by wrapping its data as a plain PNG.
Apng parse_apng(const std::string& bytes) {
    Apng apng;
    EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    std::string header;
    std::vector<std::string> frame_data;
    std::size_t at = 8;
    while (at < bytes.size()) {
        if (at + 12 > bytes.size()) {
            ADD_FAILURE() << "truncated chunk at " << at;
            break;
        }
        const std::uint32_t length = u32(bytes, at);
        const std::string type = bytes.substr(at + 4, 4), data = bytes.substr(at + 8, length);
        EXPECT_EQ(u32(bytes, at + 8 + length), crc32_of(type + data)) << "CRC of " << type << " at " << at;
        apng.chunk_types.push_back(type);
        if (type == "IHDR") header = data;
        if (type == "acTL") apng.declared_frames = u32(data, 0), apng.plays = u32(data, 4);
        if (type == "fcTL") {
            apng.sequence.push_back(u32(data, 0));
            apng.frame_sizes.emplace_back(u32(data, 4), u32(data, 8));
            frame_data.emplace_back();
        }
        if (type == "IDAT" && !frame_data.empty()) frame_data.back() += data;
        if (type == "fdAT") {
            apng.sequence.push_back(u32(data, 0));
            frame_data.back() += data.substr(4);
        }
        at += 12 + length;
    }
    for (const auto& data : frame_data)
        apng.frames.push_back(
                decode_png(std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", header) + chunk("IDAT", data) + chunk("IEND", ""), "frame"));
    return apng;
}

int rows_with_ink(const Image& image, bool first) {
    for (int i = 0; i < image.height; ++i) {
        const int y = first ? i : image.height - 1 - i;
        for (int x = 0; x < image.width; ++x)
            if (image.at(x, y) != Rgba{255, 255, 255, 255}) return y;
    }
    return -1;
}

}  // namespace

TEST(Apng, ChunksSequenceAndFramesReadBack) {
    std::vector<Image> frames;
    for (int k = 0; k < 3; ++k) {
        Image frame(9, 6, {255, 255, 255, 255});
        frame.fill_rect(k * 3, 0, k * 3 + 3, 6, {static_cast<std::uint8_t>(80 * k), 0, 200, 255});
        frames.push_back(frame);
    }
    const Apng apng = parse_apng(encode_apng(frames, 125));
    const std::vector<std::string> expected = {"IHDR", "acTL", "fcTL", "IDAT", "fcTL", "fdAT", "fcTL", "fdAT", "IEND"};
    EXPECT_EQ(apng.chunk_types, expected);
    EXPECT_EQ(apng.declared_frames, 3u);
    EXPECT_EQ(apng.plays, 0u);
    EXPECT_EQ(apng.sequence, (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
    ASSERT_EQ(apng.frames.size(), 3u);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(apng.frames[k].pixels, frames[k].pixels) << "frame " << k;
    frames.push_back(Image(4, 4));
    EXPECT_THROW(encode_apng(frames, 100), Error);  // frames of different sizes
}

TEST(Apng, RenderOrbitTurnsTheSubjectAtOneScale) {
    test::TempDir dir;
    const auto skeleton = test::source_dir() / "data" / "synthetic" / "birch_3_skeleton.ply";
    const auto r = test::run_cli("render " + test::quoted(skeleton) + " --view orbit --frames 8 --elevation 0 --size 160 --out " +
                                 test::quoted(dir / "orbit.png"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Apng apng = parse_apng(read_file(dir / "orbit.png"));
    EXPECT_EQ(apng.declared_frames, 8u);
    ASSERT_EQ(apng.frames.size(), 8u);
    EXPECT_EQ(apng.sequence.size(), 15u);  // 8 fcTL + 7 fdAT
    for (std::size_t i = 0; i < apng.sequence.size(); ++i) EXPECT_EQ(apng.sequence[i], i);
    // Plain PNG readers see frame 0.
    EXPECT_EQ(read_png(dir / "orbit.png").pixels, apng.frames[0].pixels);
    const int top = rows_with_ink(apng.frames[0], true), bottom = rows_with_ink(apng.frames[0], false);
    for (std::size_t k = 0; k < apng.frames.size(); ++k) {
        const Image& frame = apng.frames[k];
        EXPECT_EQ(frame.height, 160);
        EXPECT_EQ(frame.width, apng.frames[0].width);
        EXPECT_EQ(apng.frame_sizes[k].first, static_cast<std::uint32_t>(frame.width));
        // One scale: the tree's top and base stay on the same rows while it turns...
        EXPECT_NEAR(rows_with_ink(frame, true), top, 2) << "frame " << k;
        EXPECT_NEAR(rows_with_ink(frame, false), bottom, 2) << "frame " << k;
        // ...and it fills the frame's height (5 % margins).
        EXPECT_LE(top, 160 * 0.06);
        EXPECT_GE(bottom, 160 * 0.93);
        if (k > 0) {
            EXPECT_NE(frame.pixels, apng.frames[k - 1].pixels) << "frame " << k << " equals the one before";
        }
    }
    // The turn is a full one: frame 4 (180 degrees) is frame 0 mirrored, up to rasterisation.
    const Image &first = apng.frames[0], &half = apng.frames[4];
    int mirrored_ink = 0, ink = 0;
    for (int y = 0; y < first.height; ++y)
        for (int x = 0; x < first.width; ++x) {
            const bool a = first.at(x, y) != Rgba{255, 255, 255, 255};
            const bool b = half.at(first.width - 1 - x, y) != Rgba{255, 255, 255, 255};
            ink += a;
            mirrored_ink += a && b;
        }
    EXPECT_GT(mirrored_ink, ink * 0.6);
}
