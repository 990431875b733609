// Point-cloud readers and writers, chosen by file extension (case-insensitive):
//   .las               LAS 1.0-1.4, point formats 0-10 (core/las_io.cpp)
//   .laz               rejected with a clear message (no LAZ decoder packaged)
//   .ply               ASCII and binary PLY, any property order, scalar_* fields (core/ply_cloud_io.cpp)
//   .pcd               PCL's PCD via pcl::io (core/pcd_io.cpp)
//   .xyz .txt .csv .pts .asc   delimited text: space, comma, semicolon or tab (core/text_cloud_io.cpp)
//
// Readers keep the file's coordinates exactly: the origin is chosen from the data (LAS: the
// header offset/min corner, text: the first point, rounded) and positions are stored relative
// to it. Points with a NaN/inf coordinate are dropped and counted in source.dropped_non_finite;
// a file whose points are all non-finite is rejected. Every failure throws Error(InvalidInput)
// with the file name and what is wrong.
#pragma once

#include "core/point_cloud.hpp"

#include <filesystem>

namespace treelobes {

PointCloud read_point_cloud(const std::filesystem::path& path);

// Writes with the format given by the extension; the origin is added back (LAS: kept through
// scale/offset; float formats keep local coordinates plus a "<name>.georef.json" sidecar when
// the origin is non-zero or a CRS is known, see DESIGN.md).
void write_point_cloud(const PointCloud& cloud, const std::filesystem::path& path);

// Per-format entry points (used by the dispatchers above and by tests).
PointCloud read_las(const std::filesystem::path& path);
void write_las(const PointCloud& cloud, const std::filesystem::path& path);
PointCloud read_ply_cloud(const std::filesystem::path& path);
void write_ply_cloud(const PointCloud& cloud, const std::filesystem::path& path, bool binary = true);
PointCloud read_pcd(const std::filesystem::path& path);
void write_pcd(const PointCloud& cloud, const std::filesystem::path& path);
PointCloud read_text_cloud(const std::filesystem::path& path);
void write_text_cloud(const PointCloud& cloud, const std::filesystem::path& path);

// Lower-case extension without the dot ("las", "ply", ...).
std::string file_extension(const std::filesystem::path& path);

}  // namespace treelobes
