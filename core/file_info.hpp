// What `treelobes info` reports about a file: its kind (point cloud, mesh, skeleton, QSM, city
// model), format,
// counts, bounds in original coordinates, attributes and CRS.
#pragma once

#include "core/cloud_io.hpp"

#include <Eigen/Core>

#include <optional>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace treelobes {

struct FileInfo {
    std::string path;
    std::string kind;     // "point cloud", "mesh", "skeleton", "qsm" or "city model"
    std::string format;   // "las", "ply", "pcd", "xyz", "obj", ...
    std::string version;  // LAS "1.2", PLY "binary_little_endian", ...
    int las_point_format = -1;
    Eigen::Vector3d las_scale{0, 0, 0}, las_offset{0, 0, 0};
    std::size_t point_count = 0;  // points, mesh vertices or skeleton nodes
    std::size_t dropped_non_finite = 0;
    Eigen::Vector3d bounds_min{0, 0, 0}, bounds_max{0, 0, 0};     // original coordinates
    std::vector<std::pair<std::string, std::string>> attributes;  // name, storage type
    std::string crs;
    std::size_t face_count = 0;    // meshes
    std::size_t tip_count = 0;     // skeletons
    double total_length = 0.0;     // skeletons and QSMs, metres
    std::size_t object_count = 0;  // QSM cylinders, glTF scene nodes (trees), CityJSON city objects
    double volume = 0.0;           // QSMs: sum of cylinder volumes, cubic metres
    // LAZ input: format is "laz"; chunk size (0xFFFFFFFF = variable) and chunk count.
    std::uint32_t laz_chunk_size = 0;
    std::size_t laz_chunks = 0;
    // COPC input: octree levels and nodes with points (-1 levels when not COPC); under a
    // bounds query, the nodes that were read.
    int copc_levels = -1;
    std::size_t copc_nodes = 0, copc_nodes_read = 0;
    bool bounds_query = false;  // the counts describe the points inside a --bounds box
};

// Reads the file fully (so that a truncated file is reported) and describes it. Throws
// Error(InvalidInput) like the readers do.
// With a bounds box, point clouds are described by the points inside it (COPC: read from the
// octree nodes meeting the box only).
FileInfo describe_file(const std::filesystem::path& path, const std::optional<Box3d>& bounds = std::nullopt);

}  // namespace treelobes
