// Float formats (PLY, OBJ, glTF) are written in local coordinates. The origin travels in a
// PLY comment ("treelobes_origin x y z", read back by our readers) and, for other tools, in a
// "<stem>.georef.json" sidecar with crs_wkt, origin and units (DESIGN.md).
#pragma once

#include "core/point_cloud.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace treelobes {

std::optional<Eigen::Vector3d> read_origin_comment(const std::vector<std::string>& comments);
// Appends the origin comment when the origin is non-zero.
void write_origin_comment(const Eigen::Vector3d& origin, std::vector<std::string>& comments);
// Path of the sidecar for a data file: "<folder>/<stem>.georef.json".
std::filesystem::path georef_sidecar_path(const std::filesystem::path& data_file);
// Writes the sidecar when the origin is non-zero or a CRS is known (nothing otherwise).
// Reads "<stem>.georef.json" beside a data file when there is one: its origin and crs_wkt.
// Throws Error(InvalidInput) naming the sidecar when it exists but is not valid JSON of that form.
struct GeorefSidecar {
    Eigen::Vector3d origin{0, 0, 0};
    std::string crs_wkt;
};
std::optional<GeorefSidecar> read_georef_sidecar(const std::filesystem::path& data_file);
// The EPSG code named by a CRS: "EPSG:25832", or the last AUTHORITY["EPSG","25832"] /
// ID["EPSG",25832] of a WKT (the one of the whole CRS). Empty when there is none.
std::string epsg_code(const std::string& crs);
void write_georef_sidecar(const std::filesystem::path& data_file, const Eigen::Vector3d& origin, const Georeference& georef);

}  // namespace treelobes
