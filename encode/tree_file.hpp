// The .dbf6 file: one chain-coded tree with its levels of detail, compressed (docs/dbf6.md).
//
//   "DBF6" | version u8 | tree record | CRC-32 (zlib) of everything before it, little endian
//
// A tree record (also the unit of the .forest file) holds the code kind, the coder, the
// resolution r, the internode length l, the radius unit, the root position in double precision,
// the root radius, the LOD thresholds, and for each LOD its symbol and radii streams (coder.hpp).
// Every LOD is coded on its own, so any one decodes without the others.
#pragma once

#include "core/tree_graph.hpp"
#include "encode/coder.hpp"
#include "encode/tree_code.hpp"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace treelobes::encode {

inline constexpr std::uint8_t kTreeFileVersion = 3;  // 2: `best` contexts of fork spacing; 3: MTF-2 in `ic`
inline constexpr int kMaxLods = 16;

struct TreeFileOptions {
    EncodeOptions encode;  // resolution, internode length (0 = median edge), radius unit, kind
    int lods = 1;          // LOD 0 (full detail) plus lods - 1 reductions (lod.hpp lod_thresholds)
    Coder coder = Coder::Best;
};

// What a tree record holds, decoded or about to be written.
struct StoredTree {
    CodeKind kind = CodeKind::DBF6;
    Coder coder = Coder::Best;
    double resolution = 0.0;
    double internode_length = 0.0;
    double radius_unit = 0.001;
    Eigen::Vector3d root_position{0, 0, 0};  // world coordinates of the root vertex
    int root_radius = 0;
    std::vector<int> thresholds;  // lods - 1 values, radius units
    std::vector<ChainCode> lods;  // LOD 0 first

    CodeGeometry geometry() const;  // voxel size l / r, radius unit, root
};

// Sizes of one LOD's streams in bytes (for --stats).
struct StreamSizes {
    std::size_t symbols = 0;
    std::size_t radii = 0;
    std::size_t code_length = 0;  // symbols of the chain code
    std::size_t internodes = 0;
};

// Encodes `tree` into a StoredTree (LOD codes computed, nothing compressed yet).
StoredTree store_tree(const TreeGraph& tree, const TreeFileOptions& options, const std::string& context = "tree");

// Tree record bytes. `sizes` receives the stream sizes per LOD when given. With `prior` (forest
// files, coder best) the streams start from that model state and the record says so.
std::vector<std::uint8_t> write_tree_record(const StoredTree& tree, std::vector<StreamSizes>* sizes = nullptr,
                                            const BestPrior* prior = nullptr);
// Parses a tree record; decodes only LOD `lod` (-1: all) into `lods` (others stay empty codes).
// `position` advances past the record. Throws Error(InvalidInput) naming `context`, also for a
// record coded with a prior when `prior` is null.
StoredTree read_tree_record(std::span<const std::uint8_t> bytes, std::size_t& position, int lod, const std::string& context,
                            std::vector<StreamSizes>* sizes = nullptr, const BestPrior* prior = nullptr);

// LOD `lod` of a tree record straight to its skeleton: read_tree_record then decode_stored_tree,
// without the chain code's symbol text. Same checks and errors.
TreeGraph decode_tree_record(std::span<const std::uint8_t> bytes, std::size_t& position, int lod, const std::string& context,
                             const BestPrior* prior = nullptr);

// Whole .dbf6 files.
std::vector<std::uint8_t> write_tree_file_bytes(const StoredTree& tree, std::vector<StreamSizes>* sizes = nullptr);
StoredTree read_tree_file_bytes(std::span<const std::uint8_t> bytes, int lod, const std::string& context,
                                std::vector<StreamSizes>* sizes = nullptr);
void write_tree_file(const StoredTree& tree, const std::filesystem::path& path, std::vector<StreamSizes>* sizes = nullptr);
StoredTree read_tree_file(const std::filesystem::path& path, int lod = -1, std::vector<StreamSizes>* sizes = nullptr);

// The skeleton of LOD `lod` of a stored tree, in world coordinates through TreeGraph::origin
// (origin = root position, root at local (0, 0, 0)). Throws Error(Usage) for a LOD not stored.
TreeGraph decode_stored_tree(const StoredTree& tree, int lod, const std::string& context);

// CRC-32 (zlib polynomial) of `bytes`.
std::uint32_t crc32_of(std::span<const std::uint8_t> bytes);

// Little-endian and varint helpers shared with the .forest file.
void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v);
void put_f32(std::vector<std::uint8_t>& out, float v);
void put_f64(std::vector<std::uint8_t>& out, double v);
void put_varint(std::vector<std::uint8_t>& out, std::uint64_t v);

// Bounds-checked reader over a byte span; every failure is Error(InvalidInput) naming the context.
class ByteReader {
public:
    ByteReader(std::span<const std::uint8_t> bytes, std::size_t position, std::string context)
            : bytes_(bytes), position_(position), context_(std::move(context)) {}
    std::uint8_t u8();
    std::uint32_t u32();
    float f32();
    double f64();
    std::uint64_t varint();
    std::span<const std::uint8_t> take(std::size_t count);
    std::size_t position() const { return position_; }
    std::size_t remaining() const { return bytes_.size() - position_; }
    [[noreturn]] void fail(const std::string& what) const;
    const std::string& context() const { return context_; }

private:
    std::span<const std::uint8_t> bytes_;
    std::size_t position_;
    std::string context_;
};

}  // namespace treelobes::encode
