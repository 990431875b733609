// .dbf6 tree files as a viewer opens them: magic, version, CRC-32, then every LOD decoded to a
// skeleton. Mutations mostly stop at the CRC; dbf6_record_fuzz.cpp reaches behind it.
#include "encode/tree_file.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace treelobes::encode;
    treelobes::fuzz::expect_only_input_errors([&] {
        const StoredTree tree = read_tree_file_bytes({data, size}, -1, "fuzz input");
        for (int lod = 0; lod < static_cast<int>(tree.lods.size()); ++lod) decode_stored_tree(tree, lod, "fuzz input");
    });
    return 0;
}
