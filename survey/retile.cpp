#include "survey/retile.hpp"

#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "survey/point_pieces.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <utility>

namespace fs = std::filesystem;

namespace treelobes::survey {

namespace {

using CellKey = std::pair<std::int64_t, std::int64_t>;

// A tile's cloud: empty, with the first input's attributes, georeference and LAS choices, its
// origin at the tile's corner (positions stay small floats).
PointCloud empty_tile_like(const PointCloud& first, const Eigen::Vector3d& corner) {
    PointCloud tile = first.subset(std::vector<std::size_t>{});
    tile.origin = corner;
    tile.georef = first.georef;
    tile.source = first.source;
    tile.source.format = "las";
    tile.source.version = "1.4";
    tile.source.dropped_non_finite = 0;
    return tile;
}

}  // namespace

std::string retiled_name(const std::string& prefix, double x, double y, double size) {
    char name[128];
    if (size == std::floor(size))
        std::snprintf(name, sizeof name, "%s_%.0f_%.0f", prefix.c_str(), x, y);
    else
        std::snprintf(name, sizeof name, "%s_%.2f_%.2f", prefix.c_str(), x, y);
    return name;
}

std::vector<RetiledTile> retile(const std::vector<fs::path>& inputs, const RetileOptions& options, const fs::path& out_dir) {
    if (!(options.size > 0) || !std::isfinite(options.size)) throw Error::usage("--size must be a finite number > 0");
    std::map<CellKey, PointCloud> tiles;
    PointCloud first;
    std::string signature;
    for (std::size_t i = 0; i < inputs.size(); ++i) {
        const PointCloud cloud = read_point_cloud(inputs[i]);
        if (i == 0) {
            first = cloud.subset(std::vector<std::size_t>{});
            first.georef = cloud.georef;
            first.source = cloud.source;
            signature = attribute_signature(cloud);
        } else if (cloud.georef.crs_wkt != first.georef.crs_wkt) {
            throw Error::input(inputs[i].string(),
                               "its CRS differs from that of " + inputs[0].string() + ": reproject the inputs to one CRS first");
        } else if (attribute_signature(cloud) != signature) {
            throw Error::input(inputs[i].string(), "its attributes (" + attribute_signature(cloud) + ") differ from those of " +
                                                           inputs[0].string() + " (" + signature + ")");
        }
        std::map<CellKey, std::vector<std::size_t>> members;
        for (std::size_t p = 0; p < cloud.size(); ++p) {
            const Eigen::Vector3d g = cloud.global(p);
            members[{static_cast<std::int64_t>(std::floor(g.x() / options.size)),
                     static_cast<std::int64_t>(std::floor(g.y() / options.size))}]
                    .push_back(p);
        }
        for (const auto& [key, indices] : members) {
            auto it = tiles.find(key);
            if (it == tiles.end()) {
                const Eigen::Vector3d corner(static_cast<double>(key.first) * options.size, static_cast<double>(key.second) * options.size,
                                             std::round(cloud.origin.z()));
                it = tiles.emplace(key, empty_tile_like(first, corner)).first;
            }
            append_points(it->second, cloud.subset(indices));
        }
        log_info(inputs[i].string() + ": " + std::to_string(cloud.size()) + " points into " + std::to_string(members.size()) + " tiles");
    }
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (!fs::is_directory(out_dir)) throw Error::usage("--out " + out_dir.string() + ": cannot create the output folder");
    std::vector<RetiledTile> written;
    for (auto& [key, tile] : tiles) {
        RetiledTile result;
        result.x = static_cast<double>(key.first) * options.size;
        result.y = static_cast<double>(key.second) * options.size;
        result.points = tile.size();
        result.path = out_dir / (retiled_name(options.prefix, result.x, result.y, options.size) + ".las");
        write_las(tile, result.path);
        tile = PointCloud();  // written: free it before the next
        written.push_back(result);
    }
    return written;
}

}  // namespace treelobes::survey
