#include "survey/retile.hpp"

#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <utility>

namespace fs = std::filesystem;

namespace treelobes::survey {

namespace {

using CellKey = std::pair<std::int64_t, std::int64_t>;

template <typename T>
void append_values(std::vector<T>& into, const std::vector<T>& from) {
    into.insert(into.end(), from.begin(), from.end());
}

// The attributes a piece carries, as a comparable description.
std::string attribute_signature(const PointCloud& cloud) {
    std::string signature;
    for (const std::string& name : cloud.attribute_names()) signature += name + ";";
    for (const ExtraAttribute& extra : cloud.extras) signature += extra.name + ":" + attribute_type_name(extra.type) + ";";
    return signature;
}

// Appends `piece` to `tile`; positions move from the piece's origin to the tile's.
void append_piece(PointCloud& tile, const PointCloud& piece) {
    const Eigen::Vector3d shift = piece.origin - tile.origin;
    for (const Eigen::Vector3f& p : piece.positions) tile.positions.push_back((p.cast<double>() + shift).cast<float>());
    append_values(tile.intensity, piece.intensity);
    append_values(tile.return_number, piece.return_number);
    append_values(tile.number_of_returns, piece.number_of_returns);
    append_values(tile.classification, piece.classification);
    append_values(tile.rgb, piece.rgb);
    append_values(tile.gps_time, piece.gps_time);
    for (std::size_t k = 0; k < tile.extras.size(); ++k) append_values(tile.extras[k].values, piece.extras[k].values);
}

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
    if (size == std::floor(size)) std::snprintf(name, sizeof name, "%s_%.0f_%.0f", prefix.c_str(), x, y);
    else std::snprintf(name, sizeof name, "%s_%.2f_%.2f", prefix.c_str(), x, y);
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
            throw Error::input(inputs[i].string(), "its CRS differs from that of " + inputs[0].string() + ": reproject the inputs to one CRS first");
        } else if (attribute_signature(cloud) != signature) {
            throw Error::input(inputs[i].string(), "its attributes (" + attribute_signature(cloud) + ") differ from those of " +
                                                       inputs[0].string() + " (" + signature + ")");
        }
        std::map<CellKey, std::vector<std::size_t>> members;
        for (std::size_t p = 0; p < cloud.size(); ++p) {
            const Eigen::Vector3d g = cloud.global(p);
            members[{static_cast<std::int64_t>(std::floor(g.x() / options.size)), static_cast<std::int64_t>(std::floor(g.y() / options.size))}]
                .push_back(p);
        }
        for (const auto& [key, indices] : members) {
            auto it = tiles.find(key);
            if (it == tiles.end()) {
                const Eigen::Vector3d corner(static_cast<double>(key.first) * options.size, static_cast<double>(key.second) * options.size,
                                             std::round(cloud.origin.z()));
                it = tiles.emplace(key, empty_tile_like(first, corner)).first;
            }
            append_piece(it->second, cloud.subset(indices));
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
