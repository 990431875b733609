// PCD clouds in their three encodings: ascii, binary and binary_compressed (core/pcd_io.cpp).
#include "core/cloud_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data, size), "pcd");
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::read_pcd(path); });
    return 0;
}
