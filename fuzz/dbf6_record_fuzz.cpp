// A .dbf6 tree record behind the file's CRC-32 (the bytes read_tree_file_bytes hands on once
// the checksum matches, and the unit of a .forest file): coder, geometry, LOD thresholds, the
// symbol and radius streams, and the decoding of every LOD to a skeleton, both straight
// (decode_tree_record) and through the chain code (read_tree_record + decode_stored_tree).
#include "encode/tree_file.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace treelobes::encode;
    const std::span<const std::uint8_t> record(data, size);
    treelobes::fuzz::expect_only_input_errors([&] {
        std::size_t position = 0;
        const StoredTree tree = read_tree_record(record, position, -1, "fuzz input");
        for (int lod = 0; lod < static_cast<int>(tree.lods.size()); ++lod) decode_stored_tree(tree, lod, "fuzz input");
    });
    treelobes::fuzz::expect_only_input_errors([&] {
        std::size_t position = 0;
        decode_tree_record(record, position, 0, "fuzz input");
    });
    return 0;
}
