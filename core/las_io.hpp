// Record-level LAS/LAZ access: the uncompressed point records of a LAS or LAZ file exactly as
// stored, with the header and every VLR/EVLR verbatim. `treelobes convert` uses it to turn LAZ
// into its uncompressed twin record for record; tests use it to compare decoders byte for byte.
#pragma once

#include "core/point_cloud.hpp"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace treelobes {

struct LasRecords {
    std::vector<std::uint8_t> header;  // the public header as stored (compression bits included)
    int minor = 0;
    int point_format = 0;  // 0-10, without the LAZ bits
    std::uint16_t record_length = 0;
    std::uint64_t point_count = 0;
    bool compressed = false;
    std::vector<RawVlr> vlrs, evlrs;   // all of them, in file order
    std::vector<std::uint8_t> points;  // point_count * record_length bytes, uncompressed
};

LasRecords read_las_records(const std::filesystem::path& path);
LasRecords read_las_records(std::span<const std::uint8_t> bytes, const std::string& name);

// Writes an uncompressed LAS file with the same header fields, VLRs, EVLRs and point records;
// the LASzip and COPC records are left out (they describe compressed data). Atomic.
void write_las_records(const LasRecords& records, const std::filesystem::path& path);

}  // namespace treelobes
