// LAZ point data: the LASzip VLR and the decoding of one chunk into uncompressed LAS point
// records (rapidlasso, "LAZ specification 1.4").
//
// A LAZ file is a LAS file whose point records are replaced by independently decodable chunks.
// Point formats 0-5 use the point-wise item models version 2 (POINT10, GPSTIME11, RGB12, BYTE)
// that share one arithmetic stream per chunk; formats 6-10 use the layered models version 3
// (POINT14, RGB14, RGBNIR14, BYTE14) whose attributes live in separate per-chunk layers, so a
// reader can skip the layers it does not need (selective decompression).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace treelobes::laz {

// Item types of the LASzip VLR (spec: "LASzip VLR", item list).
enum class ItemType : std::uint16_t {
    Byte = 0,
    Point10 = 6,
    GpsTime11 = 7,
    Rgb12 = 8,
    WavePacket13 = 9,
    Point14 = 10,
    Rgb14 = 11,
    RgbNir14 = 12,
    WavePacket14 = 13,
    Byte14 = 14,
};

struct Item {
    ItemType type;
    std::uint16_t size;
    std::uint16_t version;
};

// Chunk size marking variable-size chunks (the chunk table then stores each chunk's count).
constexpr std::uint32_t kVariableChunkSize = 0xFFFFFFFFu;

// The LASzip VLR (user "laszip encoded", record 22204).
struct LaszipVlr {
    std::uint16_t compressor = 0;  // 1 point-wise (one chunk), 2 point-wise chunked, 3 layered chunked
    std::uint16_t coder = 0;       // 0 = arithmetic
    std::uint8_t version_major = 0, version_minor = 0;
    std::uint16_t version_revision = 0;
    std::uint32_t options = 0;
    std::uint32_t chunk_size = 0;  // points per chunk, or kVariableChunkSize
    std::vector<Item> items;

    bool chunked() const { return compressor >= 2; }
    bool variable_chunks() const { return chunk_size == kVariableChunkSize; }
};

// Parses the VLR payload and checks that its items are the ones `point_format` needs (in the
// LASzip order, with the supported versions) and that their sizes add up to `record_length`.
// Throws Error(InvalidInput) naming `file` and the mismatch.
LaszipVlr parse_laszip_vlr(std::span<const std::uint8_t> data, int point_format, std::uint16_t record_length, const std::string& file);

// Which parts of a point a reader needs. x, y and return numbers are always decoded (they are
// the first layer); for formats 6-10 the other layers can be skipped, their fields then keep
// the value of the chunk's first point. Formats 0-5 always decode everything.
struct LayerSelection {
    bool z = true;
    bool classification = true;
    bool flags = true;  // classification flags, scan direction, edge of flight line
    bool intensity = true;
    bool scan_angle = true;
    bool user_data = true;
    bool point_source = true;
    bool gps_time = true;
    bool rgb = true;
    bool nir = true;
    bool extra_bytes = true;

    static LayerSelection all() { return {}; }
    // x y z and classification only (plus extra bytes when `extra_bytes`).
    static LayerSelection xyz_classification(bool extra_bytes) {
        LayerSelection s;
        s.flags = s.intensity = s.scan_angle = s.user_data = s.point_source = s.gps_time = s.rgb = s.nir = false;
        s.extra_bytes = extra_bytes;
        return s;
    }
};

// Decodes one chunk of `count` points from `data` (the chunk's bytes) into `out`, which holds
// count * record_length bytes. Throws Error(InvalidInput) (naming `file` and `chunk_index`)
// when the data ends before the points do or a layer size does not fit.
void decode_chunk(const LaszipVlr& vlr, std::uint16_t record_length, std::span<const std::uint8_t> data, std::size_t count,
                  std::uint8_t* out, const LayerSelection& selection, const std::string& file, std::size_t chunk_index);

}  // namespace treelobes::laz
