#include "core/cloud_header.hpp"

#include "core/error.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

constexpr double kTextBytesPerPoint = 24.0;
constexpr std::size_t kLasHeaderBytes = 375;    // LAS 1.4; older versions are shorter
constexpr std::size_t kLasMinimumHeader = 227;  // LAS 1.0-1.2
constexpr std::size_t kLegacyCountOffset = 107, kBoundsOffset = 179, kCountOffset = 247, kLas14CountEnd = 255;

bool is_las_family(const fs::path& path) {
    const std::string extension = file_extension(path);
    return extension == "las" || extension == "laz";  // COPC files end in .copc.laz
}

template <typename T>
T little_endian_at(const std::string& bytes, std::size_t offset) {
    T value{};
    std::memcpy(&value, bytes.data() + offset, sizeof(T));  // LAS is little-endian, as is every platform we build on
    return value;
}

// The public header's bytes (at least the LAS 1.0 part); Error(InvalidInput) when it is not one.
std::string las_header(const fs::path& path) {
    if (!fs::is_regular_file(path)) throw Error::input(path.string(), "no such file");
    std::ifstream in(path, std::ios::binary);
    std::string header(kLasHeaderBytes, '\0');
    in.read(header.data(), static_cast<std::streamsize>(header.size()));
    header.resize(static_cast<std::size_t>(in.gcount()));
    if (header.size() < kLasMinimumHeader || header.compare(0, 4, "LASF") != 0)
        throw Error::input(path.string(), "not a LAS file (no LASF header)");
    return header;
}

std::size_t las_point_count(const fs::path& path) {
    const std::string header = las_header(path);
    const int minor = static_cast<unsigned char>(header[25]);
    const auto legacy = little_endian_at<std::uint32_t>(header, kLegacyCountOffset);
    if (minor >= 4 && header.size() >= kLas14CountEnd) {
        const auto count = little_endian_at<std::uint64_t>(header, kCountOffset);
        if (count > 0) return static_cast<std::size_t>(count);
    }
    return legacy;
}

std::size_t ply_point_count(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || line.rfind("ply", 0) != 0) throw Error::input(path.string(), "not a PLY file (no 'ply' line)");
    for (int lines = 0; lines < 1000 && std::getline(in, line); ++lines) {
        std::istringstream words(line);
        std::string keyword, element;
        std::size_t count = 0;
        words >> keyword >> element >> count;
        if (keyword == "element" && element == "vertex") return count;
        if (keyword == "end_header") break;
    }
    throw Error::input(path.string(), "PLY header without 'element vertex'");
}

}  // namespace

std::size_t header_point_count(const fs::path& path) {
    if (!fs::is_regular_file(path)) throw Error::input(path.string(), "no such file");
    if (is_las_family(path)) return las_point_count(path);
    if (file_extension(path) == "ply") return ply_point_count(path);
    return static_cast<std::size_t>(static_cast<double>(fs::file_size(path)) / kTextBytesPerPoint);
}

std::optional<Box3d> header_bounds(const fs::path& path) {
    if (!is_las_family(path)) {
        if (!fs::is_regular_file(path)) throw Error::input(path.string(), "no such file");
        return std::nullopt;
    }
    const std::string header = las_header(path);
    Box3d box;
    for (int k = 0; k < 3; ++k) {  // max x, min x, max y, min y, max z, min z
        box.max[k] = little_endian_at<double>(header, kBoundsOffset + 16 * static_cast<std::size_t>(k));
        box.min[k] = little_endian_at<double>(header, kBoundsOffset + 16 * static_cast<std::size_t>(k) + 8);
    }
    if (!box.min.allFinite() || !box.max.allFinite() || (box.min.array() > box.max.array()).any())
        throw Error::input(path.string(), "LAS header bounds are not finite or min > max");
    return box;
}

}  // namespace treelobes
