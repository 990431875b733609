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
void write_georef_sidecar(const std::filesystem::path& data_file, const Eigen::Vector3d& origin, const Georeference& georef);

}  // namespace treelobes
