// PLY point clouds, ascii and binary (little/big endian), through the project's one PLY parser
// (core/ply_format.cpp) and the cloud mapping of x/y/z and scalar_* fields.
#include "core/cloud_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data, size), "ply");
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::read_ply_cloud(path); });
    return 0;
}
