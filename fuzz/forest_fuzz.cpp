// .forest files (encode/forest_file.cpp): header, index, model prior, every tree record.
// With FOREST_BEHIND_CRC (forest_record_fuzz) the checksums of the index and of each record are
// recomputed before reading, so that mutations reach the index and record parsers instead of
// stopping at a checksum mismatch.
#include "encode/forest_file.hpp"
#include "fuzz_support.hpp"

#include <vector>

namespace {

using namespace treelobes::encode;

constexpr std::size_t kHeaderBytes = 4 + 1 + 4 + 4 + 3 * 8;  // docs/forest.md

void store_u32(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint32_t value) {
    for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<std::uint8_t>(value >> (8 * i));
}

// Rewrites the index checksum in place (when the header's index size fits the file).
void fix_index_crc(std::vector<std::uint8_t>& bytes) {
    if (bytes.size() < kHeaderBytes) return;
    const std::uint64_t index_size = bytes[9] | bytes[10] << 8 | bytes[11] << 16 | std::uint64_t{bytes[12]} << 24;
    const std::uint64_t index_end = kHeaderBytes + index_size;
    if (index_end + 4 > bytes.size()) return;
    store_u32(bytes, index_end, crc32_of(std::span<const std::uint8_t>(bytes).first(index_end)));
}

// Rewrites every record checksum where the parsed index says the record lies.
void fix_record_crcs(const ForestReader& reader, std::vector<std::uint8_t>& bytes) {
    for (std::size_t i = 0; i < reader.size(); ++i) {
        const ForestEntry& e = reader.entry(i);
        store_u32(bytes, e.offset + e.size, crc32_of(std::span<const std::uint8_t>(bytes).subspan(e.offset, e.size)));
    }
}

void decode_all(ForestReader& reader) {
    for (std::size_t i = 0; i < reader.size(); ++i) {
        treelobes::fuzz::expect_only_input_errors([&] {
            const StoredTree tree = reader.read(i, -1);
            for (int lod = 0; lod < static_cast<int>(tree.lods.size()); ++lod) decode_stored_tree(tree, lod, "fuzz input");
        });
        treelobes::fuzz::expect_only_input_errors([&] { reader.decode(i, 0); });
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::vector<std::uint8_t> bytes(data, data + size);
#ifdef FOREST_BEHIND_CRC
    fix_index_crc(bytes);
    treelobes::fuzz::expect_only_input_errors([&] {
        const ForestReader index(bytes, "fuzz input");
        fix_record_crcs(index, bytes);
    });
#endif
    treelobes::fuzz::expect_only_input_errors([&] {
        ForestReader reader(bytes, "fuzz input");
        decode_all(reader);
    });
    return 0;
}
