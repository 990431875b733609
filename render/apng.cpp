#include "render/apng.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <zlib.h>

#include <cstdint>
#include <string_view>

namespace treelobes::render {

namespace {

constexpr std::string_view png_signature("\x89PNG\r\n\x1a\n", 8);

void put_u32(std::string& out, std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xff));
}
void put_u16(std::string& out, std::uint16_t v) {
    out.push_back(static_cast<char>(v >> 8));
    out.push_back(static_cast<char>(v & 0xff));
}
std::uint32_t get_u32(const std::string& in, std::size_t at) {
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(in[at + k]);
    return v;
}

// A chunk: length, type, data, CRC-32 of type + data (PNG spec §5.3).
void put_chunk(std::string& out, const char (&type)[5], const std::string& data) {
    put_u32(out, static_cast<std::uint32_t>(data.size()));
    const std::string body = std::string(type, 4) + data;
    out += body;
    put_u32(out, static_cast<std::uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
}

// The IHDR data and the concatenated IDAT data of one PNG as our encoder writes it.
struct PngParts {
    std::string header;
    std::string image_data;
};

PngParts split_png(const std::string& png) {
    PngParts parts;
    std::size_t at = png_signature.size();
    while (at + 12 <= png.size()) {
        const std::uint32_t length = get_u32(png, at);
        const std::string type = png.substr(at + 4, 4);
        const std::string data = png.substr(at + 8, length);
        if (type == "IHDR")
            parts.header = data;
        else if (type == "IDAT")
            parts.image_data += data;
        at += 12 + length;
    }
    if (parts.header.size() != 13 || parts.image_data.empty()) throw Error(ExitCode::Internal, "APNG: the PNG encoder wrote no IHDR/IDAT");
    return parts;
}

// fcTL: the frame covers the whole canvas, replaces it (blend SOURCE) and stays (dispose NONE).
std::string frame_control(std::uint32_t sequence, const Image& frame, int delay_ms) {
    std::string data;
    put_u32(data, sequence);
    put_u32(data, static_cast<std::uint32_t>(frame.width));
    put_u32(data, static_cast<std::uint32_t>(frame.height));
    put_u32(data, 0);  // x offset
    put_u32(data, 0);  // y offset
    put_u16(data, static_cast<std::uint16_t>(delay_ms));
    put_u16(data, 1000);  // delay in milliseconds
    data.push_back(0);    // dispose_op NONE
    data.push_back(0);    // blend_op SOURCE
    return data;
}

}  // namespace

std::string encode_apng(const std::vector<Image>& frames, int delay_ms) {
    if (frames.empty()) throw Error(ExitCode::Internal, "APNG: no frames");
    if (delay_ms < 1 || delay_ms > 65535) throw Error::usage("APNG: frame delay must be 1..65535 ms");
    for (const auto& frame : frames)
        if (frame.width != frames.front().width || frame.height != frames.front().height)
            throw Error(ExitCode::Internal, "APNG: frames of different sizes");
    std::string out(png_signature);
    std::uint32_t sequence = 0;  // fcTL and fdAT share one sequence, starting at 0
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const PngParts parts = split_png(encode_png(frames[i]));
        if (i == 0) {
            put_chunk(out, "IHDR", parts.header);
            std::string animation;
            put_u32(animation, static_cast<std::uint32_t>(frames.size()));
            put_u32(animation, 0);  // play forever
            put_chunk(out, "acTL", animation);
        }
        put_chunk(out, "fcTL", frame_control(sequence++, frames[i], delay_ms));
        if (i == 0) {
            put_chunk(out, "IDAT", parts.image_data);
        } else {
            std::string data;
            put_u32(data, sequence++);
            put_chunk(out, "fdAT", data + parts.image_data);
        }
    }
    put_chunk(out, "IEND", "");
    return out;
}

void write_apng(const std::vector<Image>& frames, int delay_ms, const std::filesystem::path& path) {
    write_file_atomically(path, encode_apng(frames, delay_ms));
}

}  // namespace treelobes::render
