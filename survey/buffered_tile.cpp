#include "survey/buffered_tile.hpp"

#include "core/cloud_header.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "survey/point_pieces.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace fs = std::filesystem;

namespace treelobes::survey {

namespace {

// The two numbers that end a retile name ("tile_500040_5400000" -> 500040, 5400000).
bool corner_of_name(const std::string& name, double& x, double& y) {
    const std::size_t last = name.rfind('_');
    if (last == std::string::npos || last == 0) return false;
    const std::size_t before = name.rfind('_', last - 1);
    if (before == std::string::npos) return false;
    const std::string xs = name.substr(before + 1, last - before - 1), ys = name.substr(last + 1);
    char* end = nullptr;
    x = std::strtod(xs.c_str(), &end);
    if (xs.empty() || *end != '\0') return false;
    y = std::strtod(ys.c_str(), &end);
    return !ys.empty() && *end == '\0' && std::isfinite(x) && std::isfinite(y);
}

bool same_file(const fs::path& a, const fs::path& b) {
    std::error_code ec;
    return fs::equivalent(a, b, ec);
}

}  // namespace

bool TileCore::holds(double x, double y) const {
    if (half_open) return x >= min_x && x < max_x && y >= min_y && y < max_y;
    return x >= min_x && x <= max_x && y >= min_y && y <= max_y;
}

TileCore core_from_retile_name(const fs::path& tile, double size) {
    double x = 0, y = 0;
    if (!corner_of_name(tile.stem().string(), x, y))
        throw Error::usage("--tile-size: " + tile.filename().string() +
                           " is not named <prefix>_<x>_<y> by `treelobes retile`; "
                           "leave --tile-size out to take the tile's point bounds as its core");
    return {x, y, x + size, y + size, true, "retile name"};
}

std::optional<TileCore> core_from_header(const fs::path& tile) {
    const auto bounds = header_bounds(tile);
    if (!bounds) return std::nullopt;
    return TileCore{bounds->min.x(), bounds->min.y(), bounds->max.x(), bounds->max.y(), false, "header bounds"};
}

TileCore core_from_points(const PointCloud& cloud) {
    const auto [low, high] = cloud.bounds();
    const Eigen::Vector3d lo = cloud.origin + low.cast<double>(), hi = cloud.origin + high.cast<double>();
    return {lo.x(), lo.y(), hi.x(), hi.y(), false, "point bounds"};
}

Box3d buffered_box(const TileCore& core, double buffer) {
    const double inf = std::numeric_limits<double>::infinity();
    return {{core.min_x - buffer, core.min_y - buffer, -inf}, {core.max_x + buffer, core.max_y + buffer, inf}};
}

std::size_t estimate_buffer_points(const fs::path& input, const std::optional<TileCore>& core, double buffer,
                                   const std::vector<fs::path>& candidates) {
    double points = 0;
    for (const fs::path& neighbour : candidates) {
        if (same_file(neighbour, input)) continue;
        const auto count = static_cast<double>(header_point_count(neighbour));
        const auto bounds = header_bounds(neighbour);
        if (!bounds || !core) {
            points += count;
            continue;
        }
        const Box3d box = buffered_box(*core, buffer);
        const Eigen::Vector2d lo = bounds->min.head<2>().cwiseMax(box.min.head<2>()),
                              hi = bounds->max.head<2>().cwiseMin(box.max.head<2>());
        if ((lo.array() > hi.array()).any()) continue;
        const Eigen::Vector2d extent = bounds->max.head<2>() - bounds->min.head<2>();
        const double area = extent.x() * extent.y();
        points += area > 0 ? count * (hi - lo).prod() / area : count;
    }
    return static_cast<std::size_t>(std::ceil(points));
}

BufferedTile add_buffer(PointCloud tile, const fs::path& input, const TileCore& core, double buffer,
                        const std::vector<fs::path>& candidates) {
    BufferedTile result;
    result.own_points = tile.size();
    const Box3d box = buffered_box(core, buffer);
    const std::string signature = attribute_signature(tile);
    for (const fs::path& neighbour : candidates) {
        if (same_file(neighbour, input)) continue;
        if (const auto bounds = header_bounds(neighbour); bounds && !box.intersects(bounds->min, bounds->max)) {
            ++result.neighbours_skipped;
            continue;
        }
        CloudReadOptions read;
        read.bounds = box;
        const PointCloud points = read_point_cloud(neighbour, read);
        if (points.empty()) continue;
        if (points.georef.crs_wkt != tile.georef.crs_wkt)
            throw Error::input(neighbour.string(), "its CRS differs from that of the tile " + input.string() + ": a buffer needs one CRS");
        if (attribute_signature(points) != signature)
            throw Error::input(neighbour.string(), "its attributes (" + attribute_signature(points) + ") differ from those of the tile " +
                                                           input.string() + " (" + signature + ")");
        std::vector<std::size_t> outside_core;
        for (std::size_t i = 0; i < points.size(); ++i) {
            const Eigen::Vector3d g = points.global(i);
            if (!core.holds(g.x(), g.y())) outside_core.push_back(i);
        }
        if (outside_core.empty()) continue;
        append_points(tile, points.subset(outside_core));
        result.neighbours_read.push_back(neighbour);
    }
    std::sort(result.neighbours_read.begin(), result.neighbours_read.end());
    log_info(input.string() + ": " + std::to_string(tile.size() - result.own_points) + " buffer points from " +
             std::to_string(result.neighbours_read.size()) + " neighbouring tiles");
    result.cloud = std::move(tile);
    return result;
}

}  // namespace treelobes::survey
