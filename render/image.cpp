#include "render/image.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <png.h>

#include <algorithm>
#include <csetjmp>
#include <cstring>
#include <memory>
#include <sstream>

namespace treelobes::render {

Image::Image(int w, int h, Rgba background) : width(w), height(h) {
    if (w <= 0 || h <= 0 || w > 16384 || h > 16384)
        throw Error::usage("image size must be 1..16384 pixels per side, got " + std::to_string(w) + "x" + std::to_string(h));
    pixels.resize(static_cast<std::size_t>(w) * h * 4);
    for (std::size_t i = 0; i < pixels.size(); i += 4) std::memcpy(&pixels[i], background.data(), 4);
}

Rgba Image::at(int x, int y) const {
    const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 4;
    return {pixels[i], pixels[i + 1], pixels[i + 2], pixels[i + 3]};
}

void Image::set(int x, int y, Rgba colour) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    std::memcpy(&pixels[(static_cast<std::size_t>(y) * width + x) * 4], colour.data(), 4);
}

void Image::fill_rect(int x0, int y0, int x1, int y1, Rgba colour) {
    for (int y = std::max(0, y0); y < std::min(height, y1); ++y)
        for (int x = std::max(0, x0); x < std::min(width, x1); ++x) set(x, y, colour);
}

namespace {

// libpng reports errors by longjmp (exceptions must not cross its C frames): the handlers
// keep the message, the callers turn it into an Error after setjmp returns.
struct PngIo {
    std::ostream* out = nullptr;
    const std::string* bytes = nullptr;
    std::size_t position = 0;
    std::string error;
};

void png_to_stream(png_structp png, png_bytep data, png_size_t length) {
    static_cast<PngIo*>(png_get_io_ptr(png))->out->write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(length));
}
void png_flush_stream(png_structp) {}

void png_from_memory(png_structp png, png_bytep data, png_size_t length) {
    auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
    if (io->position + length > io->bytes->size()) png_error(png, "truncated PNG");
    std::memcpy(data, io->bytes->data() + io->position, length);
    io->position += length;
}

void png_fail(png_structp png, png_const_charp message) {
    static_cast<PngIo*>(png_get_error_ptr(png))->error = message;
    png_longjmp(png, 1);
}
void png_warn(png_structp, png_const_charp) {}

// Returns false (with io.error set) when libpng failed.
bool encode_png_into(const Image& image, PngIo& io) {
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &io, png_fail, png_warn);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        io.error = "out of memory";
        png_destroy_write_struct(&png, &info);
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return false;
    }
    png_set_write_fn(png, &io, png_to_stream, png_flush_stream);
    png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < image.height; ++y)
        png_write_row(png, const_cast<png_bytep>(&image.pixels[static_cast<std::size_t>(y) * image.width * 4]));
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return true;
}

bool decode_png_from(PngIo& io, Image& image) {
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, png_fail, png_warn);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        io.error = "out of memory";
        png_destroy_read_struct(&png, &info, nullptr);
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, nullptr);
        return false;
    }
    png_set_read_fn(png, &io, png_from_memory);
    png_read_info(png, info);
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_gray_to_rgb(png);
    png_set_add_alpha(png, 0xff, PNG_FILLER_AFTER);
    png_read_update_info(png, info);
    const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
    if (width == 0 || height == 0 || width > 16384 || height > 16384) png_error(png, "unsupported image size");
    image.width = static_cast<int>(width);
    image.height = static_cast<int>(height);
    image.pixels.assign(static_cast<std::size_t>(width) * height * 4, 0);
    for (png_uint_32 y = 0; y < height; ++y) png_read_row(png, &image.pixels[static_cast<std::size_t>(y) * width * 4], nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    return true;
}

}  // namespace

void write_png(const Image& image, const std::filesystem::path& path) {
    write_atomically(path, [&](std::ostream& out) {
        PngIo io;
        io.out = &out;
        if (!encode_png_into(image, io)) throw Error::input(path.string(), "cannot encode PNG: " + io.error);
    });
}

std::string encode_png(const Image& image) {
    std::ostringstream out;
    PngIo io;
    io.out = &out;
    if (!encode_png_into(image, io)) throw Error(ExitCode::Internal, "cannot encode PNG: " + io.error);
    return std::move(out).str();
}

Image decode_png(const std::string& bytes, const std::string& what) {
    if (bytes.size() < 8 || png_sig_cmp(reinterpret_cast<png_const_bytep>(bytes.data()), 0, 8) != 0)
        throw Error::input(what, "not a PNG file");
    PngIo io;
    io.bytes = &bytes;
    Image image;
    if (!decode_png_from(io, image)) throw Error::input(what, "cannot decode PNG: " + io.error);
    return image;
}

Image read_png(const std::filesystem::path& path) { return decode_png(read_file(path), path.string()); }

Image side_by_side(const std::vector<Image>& images, Rgba background) {
    int width = 0, height = 0;
    for (const auto& image : images) {
        width += image.width;
        height = std::max(height, image.height);
    }
    Image out(std::max(width, 1), std::max(height, 1), background);
    int x0 = 0;
    for (const auto& image : images) {
        for (int y = 0; y < image.height; ++y)
            std::memcpy(&out.pixels[(static_cast<std::size_t>(y) * out.width + x0) * 4],
                        &image.pixels[static_cast<std::size_t>(y) * image.width * 4], static_cast<std::size_t>(image.width) * 4);
        x0 += image.width;
    }
    return out;
}

}  // namespace treelobes::render
