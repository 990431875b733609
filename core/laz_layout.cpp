// LAZ chunk table and COPC hierarchy; see laz_layout.hpp.
#include "core/laz_layout.hpp"

#include "core/laz_codec.hpp"
#include "core/little_endian.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace treelobes::laz {

namespace {

constexpr std::uint64_t kUnknownTableOffset = 0xFFFFFFFFFFFFFFFFull;  // written by streaming encoders
// A chunk stores its first point raw and then at least a fraction of a bit per point; no real
// file comes near 1000 points per compressed byte, so larger claims are corruption (and would
// otherwise make a tiny file allocate gigabytes).
constexpr std::uint64_t kMaxPointsPerByte = 1000;

std::uint64_t locate_chunk_table(InputFile& file, std::uint64_t offset_to_points) {
    const auto pointer = file.read(offset_to_points, 8, "LAZ chunk table offset");
    std::uint64_t table = load<std::uint64_t>(pointer.data());
    if (table == kUnknownTableOffset) {
        // The encoder could not seek back: the offset is stored in the last 8 bytes instead.
        if (file.size() < 8) file.fail("LAZ chunk table offset is missing");
        const auto tail = file.read(file.size() - 8, 8, "LAZ chunk table offset at the end of the file");
        table = load<std::uint64_t>(tail.data());
    }
    return table;
}

}  // namespace

std::vector<Chunk> read_chunk_table(InputFile& file, const LaszipVlr& vlr, std::uint64_t offset_to_points, std::uint64_t data_end,
                                    std::uint64_t point_count, std::uint16_t record_length) {
    std::vector<Chunk> chunks;
    if (point_count == 0) return chunks;
    if (!vlr.chunked()) {
        // Compressor 1: one stream with every point, no chunk table.
        if (data_end <= offset_to_points) file.fail("LAZ point data is empty but " + std::to_string(point_count) + " points are declared");
        chunks.push_back({offset_to_points, data_end - offset_to_points, 0, point_count});
    } else {
        const std::uint64_t first_chunk = offset_to_points + 8;
        const std::uint64_t table = locate_chunk_table(file, offset_to_points);
        if (table < first_chunk || table > file.size() || file.size() - table < 8)
            file.fail("LAZ chunk table offset " + std::to_string(table) + " lies outside the file (point data from byte " +
                      std::to_string(first_chunk) + ", file " + std::to_string(file.size()) + " bytes; truncated?)");
        const auto head = file.read(table, 8, "LAZ chunk table header");
        const std::uint32_t version = load<std::uint32_t>(head.data());
        const std::uint64_t count = load<std::uint32_t>(head.data() + 4);
        if (version != 0) file.fail("LAZ chunk table version " + std::to_string(version) + ", expected 0");
        // Every chunk holds at least its raw first point.
        if (count == 0 || count > (table - first_chunk) / record_length)
            file.fail("LAZ chunk table declares " + std::to_string(count) + " chunks, which cannot fit in the " +
                      std::to_string(table - first_chunk) + " bytes of point data");
        // An entry takes at most ~10 compressed bytes; EVLRs may follow the table.
        const std::uint64_t available = file.size() - (table + 8);
        const auto entries = file.read(table + 8, static_cast<std::size_t>(std::min(available, count * 12 + 16)), "LAZ chunk table");
        // Entries are differences to the previous entry, integer-compressed (32 bits, 2 contexts):
        // context 0 the point count (variable chunks only), context 1 the byte count.
        ArithmeticDecoder decoder;
        decoder.init(entries.data(), entries.size());
        IntegerDecompressor ic(decoder, 32, 2);
        std::uint32_t previous_count = 0, previous_bytes = 0;
        std::uint64_t offset = first_chunk, first_point = 0;
        for (std::uint64_t i = 0; i < count; ++i) {
            std::uint64_t points = vlr.chunk_size;
            if (vlr.variable_chunks()) {
                previous_count = static_cast<std::uint32_t>(ic.decompress(static_cast<std::int32_t>(previous_count), 0));
                points = previous_count;
            }
            previous_bytes = static_cast<std::uint32_t>(ic.decompress(static_cast<std::int32_t>(previous_bytes), 1));
            if (!vlr.variable_chunks()) points = std::min<std::uint64_t>(points, point_count - std::min(point_count, first_point));
            chunks.push_back({offset, previous_bytes, first_point, points});
            offset += previous_bytes;
            first_point += points;
        }
        if (decoder.overrun() > 4) file.fail("LAZ chunk table is truncated");
        if (offset > table)
            file.fail("LAZ chunk table: the chunks end at byte " + std::to_string(offset) + ", past the chunk table at byte " +
                      std::to_string(table) + " (corrupt table)");
    }
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < chunks.size(); ++i) {
        const Chunk& c = chunks[i];
        if (c.count == 0 && i + 1 < chunks.size()) file.fail("LAZ chunk " + std::to_string(i) + " holds no points");
        if (c.bytes == 0 && c.count > 0)
            file.fail("LAZ chunk " + std::to_string(i) + " is empty but holds " + std::to_string(c.count) + " points");
        if (c.count > c.bytes * kMaxPointsPerByte)
            file.fail("LAZ chunk " + std::to_string(i) + " claims " + std::to_string(c.count) + " points in " + std::to_string(c.bytes) +
                      " bytes (corrupt chunk table)");
        total += c.count;
    }
    if (total != point_count)
        file.fail("LAZ chunk table holds " + std::to_string(total) + " points, the header declares " + std::to_string(point_count));
    return chunks;
}

CopcInfo parse_copc_info(std::span<const std::uint8_t> data, const std::string& file) {
    if (data.size() < 160) throw Error::input(file, "COPC info VLR is " + std::to_string(data.size()) + " bytes, expected 160");
    const std::uint8_t* p = data.data();
    CopcInfo info;
    for (int k = 0; k < 3; ++k) info.center[k] = load<double>(p + 8 * k);
    info.halfsize = load<double>(p + 24);
    info.spacing = load<double>(p + 32);
    info.root_hierarchy_offset = load<std::uint64_t>(p + 40);
    info.root_hierarchy_size = load<std::uint64_t>(p + 48);
    info.gps_time_min = load<double>(p + 56);
    info.gps_time_max = load<double>(p + 64);
    if (!(info.halfsize > 0) || !std::isfinite(info.halfsize) || !info.center.allFinite())
        throw Error::input(file, "COPC info VLR: octree centre/half size are not finite positive numbers");
    return info;
}

std::vector<CopcNode> read_copc_hierarchy(InputFile& file, const CopcInfo& info) {
    constexpr std::size_t kEntrySize = 32;  // key (4 x int32), offset (uint64), byte size, point count (int32)
    std::vector<CopcNode> nodes;
    std::vector<std::pair<std::uint64_t, std::uint64_t>> pending{{info.root_hierarchy_offset, info.root_hierarchy_size}};
    std::set<std::uint64_t> visited;  // a page listed twice (corrupt file) is read once: no cycles
    std::uint64_t first_point = 0, page_bytes = 0;
    while (!pending.empty()) {
        const auto [offset, size] = pending.back();
        pending.pop_back();
        if (!visited.insert(offset).second) continue;
        if (size % kEntrySize != 0)
            file.fail("COPC hierarchy page at byte " + std::to_string(offset) + " is " + std::to_string(size) +
                      " bytes, not a multiple of 32");
        // Pages do not overlap, so together they fit in the file; more means a corrupt hierarchy
        // that would otherwise make the reader go over the same bytes again and again.
        page_bytes += size;
        if (size > file.size() || page_bytes > file.size())
            file.fail("COPC hierarchy pages at byte " + std::to_string(offset) + " add up to more than the file holds");
        const auto page = file.read(offset, static_cast<std::size_t>(size), "COPC hierarchy page");
        for (std::size_t pos = 0; pos < page.size(); pos += kEntrySize) {
            const std::uint8_t* e = page.data() + pos;
            CopcNode node;
            node.level = load<std::int32_t>(e);
            node.x = load<std::int32_t>(e + 4);
            node.y = load<std::int32_t>(e + 8);
            node.z = load<std::int32_t>(e + 12);
            const std::uint64_t entry_offset = load<std::uint64_t>(e + 16);
            const std::int32_t byte_size = load<std::int32_t>(e + 24);
            const std::int32_t point_count = load<std::int32_t>(e + 28);
            if (node.level < 0 || node.level > 30)
                file.fail("COPC hierarchy entry with level " + std::to_string(node.level) + " (expected 0-30)");
            if (point_count == -1) {  // a child hierarchy page
                if (byte_size < 0) file.fail("COPC hierarchy page reference with negative size");
                pending.emplace_back(entry_offset, static_cast<std::uint64_t>(byte_size));
                continue;
            }
            if (point_count <= 0) continue;  // a node without points
            if (byte_size <= 0 || entry_offset > file.size() || static_cast<std::uint64_t>(byte_size) > file.size() - entry_offset)
                file.fail("COPC node " + std::to_string(node.level) + "-" + std::to_string(node.x) + "-" + std::to_string(node.y) + "-" +
                          std::to_string(node.z) + " points outside the file");
            const double side = 2 * info.halfsize / std::ldexp(1.0, node.level);
            const Eigen::Vector3d corner = info.center.array() - info.halfsize;
            node.min = corner + side * Eigen::Vector3d(node.x, node.y, node.z);
            node.max = node.min.array() + side;
            node.chunk = {entry_offset, static_cast<std::uint64_t>(byte_size), first_point, static_cast<std::uint64_t>(point_count)};
            first_point += static_cast<std::uint64_t>(point_count);
            nodes.push_back(node);
        }
    }
    return nodes;
}

}  // namespace treelobes::laz
