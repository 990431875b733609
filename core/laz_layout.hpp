// Where the compressed chunks of a LAZ file are (the chunk table, rapidlasso "LAZ specification
// 1.4", section "chunk table") and, for COPC files, the octree of chunks (ASPRS/Hobu "COPC 1.0":
// the "copc" info VLR and the hierarchy pages).
#pragma once

#include "core/input_file.hpp"
#include "core/laz_chunk.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes::laz {

struct Chunk {
    std::uint64_t offset = 0;  // absolute file offset of the chunk's bytes
    std::uint64_t bytes = 0;
    std::uint64_t first_point = 0;  // index of its first point in the file
    std::uint64_t count = 0;        // points in the chunk
};

// Reads and checks the chunk table of the point data in [offset_to_points, data_end): every chunk
// must lie inside that region, the counts must add up to `point_count`, and no chunk may claim
// more points than its bytes could plausibly hold. Throws Error(InvalidInput) naming the file.
std::vector<Chunk> read_chunk_table(InputFile& file, const LaszipVlr& vlr, std::uint64_t offset_to_points, std::uint64_t data_end,
                                    std::uint64_t point_count, std::uint16_t record_length);

// COPC 1.0 "copc info" VLR (user "copc", record 1, 160 bytes).
struct CopcInfo {
    Eigen::Vector3d center{0, 0, 0};
    double halfsize = 0, spacing = 0;
    std::uint64_t root_hierarchy_offset = 0, root_hierarchy_size = 0;
    double gps_time_min = 0, gps_time_max = 0;
};
CopcInfo parse_copc_info(std::span<const std::uint8_t> data, const std::string& file);

// One octree node with points: its key (level, x, y, z), cube and chunk.
struct CopcNode {
    std::int32_t level = 0, x = 0, y = 0, z = 0;
    Eigen::Vector3d min{0, 0, 0}, max{0, 0, 0};
    Chunk chunk;  // first_point is the node's position in hierarchy order
};

// Reads every hierarchy page reachable from the root; returns the nodes that hold points.
std::vector<CopcNode> read_copc_hierarchy(InputFile& file, const CopcInfo& info);

}  // namespace treelobes::laz
