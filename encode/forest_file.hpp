// The .forest file: many chain-coded trees with their placements and an index for random access
// (docs/forest.md). Strnad et al. 2020, §4, Experiment 3 stores a forest scene as compressed trees plus tree
// locations and orientations; here every tree is a .dbf6 tree record (tree_file.hpp).
//
//   header  "DBFF" | version u8 | tree count u32 | index bytes u32 | forest origin f64 x3
//   index   model prior (varint size + bytes; coder best: the adaptive models' initial state,
//           trained on all trees of the file, so small trees do not each pay for learning)
//           per tree: record bytes (varint), position - origin (f32 x3), azimuth (f32, radians
//           about +z), name (varint length + UTF-8)
//           CRC-32 of header and index
//   records per tree: tree record | CRC-32 of the record
//
// A reader parses the header and the index, then seeks straight to one record: reading tree i
// touches neither the bytes nor the decoding of any other tree. Each record has its own
// checksum, so a damaged tree is reported without condemning the others.
#pragma once

#include "encode/tree_file.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace treelobes::encode {

inline constexpr std::uint8_t kForestFileVersion = 3;  // 2: `best` contexts of fork spacing; 3: MTF-2 in `ic`
inline constexpr std::uint32_t kMaxForestTrees = 1u << 24;

// A tree to place: its skeleton in its own frame, rotated by `azimuth` about +z and then moved
// by `position` (world coordinates).
struct ForestTree {
    TreeGraph skeleton;
    Eigen::Vector3d position{0, 0, 0};
    float azimuth = 0.0f;
    std::string name;
};

struct ForestEntry {
    std::string name;
    Eigen::Vector3d position{0, 0, 0};
    float azimuth = 0.0f;
    std::uint64_t offset = 0;  // of the record in the file
    std::uint64_t size = 0;    // record bytes, without its CRC
};

struct ForestStats {
    std::size_t header_and_index = 0;
    std::vector<std::vector<StreamSizes>> trees;  // per tree, per LOD
};

// Encodes every tree with `options` (trees are independent: coded in parallel, output identical).
std::vector<std::uint8_t> write_forest_bytes(const std::vector<ForestTree>& trees, const TreeFileOptions& options,
                                             ForestStats* stats = nullptr);
void write_forest_file(const std::vector<ForestTree>& trees, const TreeFileOptions& options, const std::filesystem::path& path,
                       ForestStats* stats = nullptr);

// The skeleton of a stored forest tree in world coordinates: origin = the tree's position, local
// positions rotated by its azimuth.
TreeGraph place_tree(TreeGraph skeleton, const ForestEntry& entry);

// Random access over a .forest file (or over its bytes in memory).
class ForestReader {
public:
    explicit ForestReader(const std::filesystem::path& path);
    ForestReader(std::vector<std::uint8_t> bytes, std::string context);

    std::size_t size() const { return entries_.size(); }
    const ForestEntry& entry(std::size_t i) const;
    const Eigen::Vector3d& origin() const { return origin_; }
    std::size_t index_bytes() const { return index_end_; }
    // Tree i with LOD `lod` decoded (-1: all LODs). Throws Error(Usage) for i out of range.
    StoredTree read(std::size_t i, int lod = 0, std::vector<StreamSizes>* sizes = nullptr);
    // Tree i's LOD `lod` as a placed skeleton.
    TreeGraph decode(std::size_t i, int lod = 0);

private:
    void parse_index(std::span<const std::uint8_t> head, std::uint64_t file_size);
    std::vector<std::uint8_t> record_bytes(std::size_t i);

    std::string context_;
    std::ifstream file_;
    std::vector<std::uint8_t> memory_;  // the whole file when read from memory
    bool in_memory_ = false;
    Eigen::Vector3d origin_{0, 0, 0};
    std::vector<ForestEntry> entries_;
    std::size_t index_end_ = 0;
    std::shared_ptr<const BestPrior> prior_;  // the forest's model prior (coder best), if any
};

}  // namespace treelobes::encode
