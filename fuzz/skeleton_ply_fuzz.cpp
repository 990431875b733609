// Skeleton PLY (vertex x y z radius, edge vertex1 vertex2): the tree checks behind the PLY
// parser (one root, parents before children, no cycles).
#include "core/skeleton_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data, size), "ply");
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::read_skeleton_ply(path); });
    return 0;
}
