#include "survey/memory_estimate.hpp"

#include "core/cloud_io.hpp"
#include "core/error.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace treelobes::survey {

namespace {

constexpr double kTextBytesPerPoint = 24.0;

template <typename T>
T little_endian_at(const std::string& bytes, std::size_t offset) {
    T value{};
    std::memcpy(&value, bytes.data() + offset, sizeof(T));  // LAS is little-endian, as is every platform we build on
    return value;
}

std::size_t las_point_count(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::string header(375, '\0');
    in.read(header.data(), static_cast<std::streamsize>(header.size()));
    const auto got = static_cast<std::size_t>(in.gcount());
    if (got < 227 || header.compare(0, 4, "LASF") != 0) throw Error::input(path.string(), "not a LAS file (no LASF header)");
    const int minor = static_cast<unsigned char>(header[25]);
    const auto legacy = little_endian_at<std::uint32_t>(header, 107);
    if (minor >= 4 && got >= 255) {
        const auto count = little_endian_at<std::uint64_t>(header, 247);
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
    const std::string extension = file_extension(path);
    if (extension == "las") return las_point_count(path);
    if (extension == "ply") return ply_point_count(path);
    return static_cast<std::size_t>(static_cast<double>(fs::file_size(path)) / kTextBytesPerPoint);
}

double default_memory_budget_bytes() {
    const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page_size <= 0) return 4.0 * 1024 * 1024 * 1024;  // unknown: a modest 4 GiB
    return 0.5 * static_cast<double>(pages) * static_cast<double>(page_size);
}

double parse_memory_size(const std::string& text) {
    double value = 0;
    char unit = 0;
    char rest = 0;
    const int fields = std::sscanf(text.c_str(), "%lf%c%c", &value, &unit, &rest);
    double factor = 1;
    if (fields == 2) {
        switch (unit) {
            case 'k': case 'K': factor = 1024.0; break;
            case 'm': case 'M': factor = 1024.0 * 1024; break;
            case 'g': case 'G': factor = 1024.0 * 1024 * 1024; break;
            case 't': case 'T': factor = 1024.0 * 1024 * 1024 * 1024; break;
            default: factor = 0;
        }
    }
    if (fields < 1 || fields > 2 || factor == 0 || !std::isfinite(value) || value <= 0)
        throw Error::usage("--max-memory " + text + ": expected a size such as 512M, 8G or a number of bytes");
    return value * factor;
}

std::optional<std::string> refuse_if_too_big(const fs::path& tile, double budget_bytes) {
    return memory_refusal(header_point_count(tile), kTileBytesPerPoint, budget_bytes);
}

std::optional<std::string> memory_refusal(std::size_t points, double bytes_per_point, double budget_bytes) {
    const double estimate = static_cast<double>(points) * bytes_per_point;
    if (estimate <= budget_bytes) return std::nullopt;
    char message[512];
    std::snprintf(message, sizeof message,
                  "%zu points need about %.1f GiB (%.0f bytes per point), more than the memory budget of %.1f GiB: "
                  "cut it with `treelobes retile --size METRES` into smaller tiles, or raise --max-memory",
                  points, estimate / (1024.0 * 1024 * 1024), bytes_per_point, budget_bytes / (1024.0 * 1024 * 1024));
    return std::string(message);
}

}  // namespace treelobes::survey
