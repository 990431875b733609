// Point-cloud readers and writers, chosen by file extension (case-insensitive):
//   .las               LAS 1.0-1.4, point formats 0-10 (core/las_io.cpp)
//   .laz .copc.laz     LASzip-compressed LAS and COPC, decoded natively (core/laz_*.cpp, docs/laz.md)
//   .ply               ASCII and binary PLY, any property order, scalar_* fields (core/ply_cloud_io.cpp)
//   .pcd               PCD: ascii, binary, binary_compressed; read by our parser, written by PCL (core/pcd_io.cpp)
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
#include <optional>
#include <span>

namespace treelobes {

// An axis-aligned box in original (georeferenced) coordinates; a 2-D box has z = -inf..inf.
struct Box3d {
    Eigen::Vector3d min, max;
    bool contains(const Eigen::Vector3d& p) const { return (p.array() >= min.array()).all() && (p.array() <= max.array()).all(); }
    bool intersects(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
        return (lo.array() <= max.array()).all() && (hi.array() >= min.array()).all();
    }
};

struct CloudReadOptions {
    // Keep only the points inside the box. COPC files read only the octree nodes that intersect
    // it; other formats read everything and filter.
    std::optional<Box3d> bounds;
    // LAS/LAZ: keep positions, classification and extra attributes only. For LAZ point formats
    // 6-10 the other layers (intensity, GPS time, RGB, flags, ...) are skipped undecoded.
    bool xyz_classification_only = false;
};

PointCloud read_point_cloud(const std::filesystem::path& path, const CloudReadOptions& options = {});

// Writes with the format given by the extension; the origin is added back (LAS: kept through
// scale/offset; float formats keep local coordinates plus a "<name>.georef.json" sidecar when
// the origin is non-zero or a CRS is known, see DESIGN.md).
void write_point_cloud(const PointCloud& cloud, const std::filesystem::path& path);

// Per-format entry points (used by the dispatchers above and by tests).
PointCloud read_las(const std::filesystem::path& path, const CloudReadOptions& options = {});
// The same from bytes in memory (`name` labels error messages); e.g. for fuzzing the reader.
PointCloud read_las_buffer(std::span<const std::uint8_t> bytes, const std::string& name, const CloudReadOptions& options = {});
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
