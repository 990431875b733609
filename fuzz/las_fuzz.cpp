// LAS reader: public header, VLRs and EVLRs, extra-bytes descriptors, point records of
// formats 0-10 (core/las_io.cpp).
#include "core/cloud_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data, size), "las");
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::read_las(path); });
    return 0;
}
