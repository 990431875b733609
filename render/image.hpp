// RGBA images and PNG output (libpng), for previews, lobe textures and plots.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::render {

using Rgba = std::array<std::uint8_t, 4>;

struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> pixels;  // row-major RGBA, row 0 at the top

    Image() = default;
    Image(int w, int h, Rgba background = {0, 0, 0, 0});
    Rgba at(int x, int y) const;
    void set(int x, int y, Rgba colour);                          // ignores pixels outside the image
    void fill_rect(int x0, int y0, int x1, int y1, Rgba colour);  // [x0, x1) x [y0, y1)
};

// Writes an 8-bit RGBA PNG atomically; throws Error(InvalidInput) naming the path on failure.
void write_png(const Image& image, const std::filesystem::path& path);
// Reads an 8-bit RGBA/RGB/grey PNG (converted to RGBA).
Image read_png(const std::filesystem::path& path);
// The bytes of an 8-bit RGBA PNG (for files that embed images, and APNG frames).
std::string encode_png(const Image& image);
// Decodes PNG bytes; `what` names the source in the error.
Image decode_png(const std::string& bytes, const std::string& what);

// Places images side by side (same height; shorter ones are padded at the bottom).
Image side_by_side(const std::vector<Image>& images, Rgba background = {255, 255, 255, 255});

}  // namespace treelobes::render
