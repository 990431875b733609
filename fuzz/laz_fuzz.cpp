// LAZ and COPC reader from memory: LASzip VLR and item list, chunk table, arithmetic decoder and
// the point10 v2 / layered point14 v3 item models, COPC hierarchy pages (core/las_io.cpp and the
// laz_* modules). Seeds: the real LAZ files of ../shared/data (scripts/fuzz.sh adds them).
#include "core/cloud_io.hpp"
#include "fuzz_support.hpp"

#include <span>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::span<const std::uint8_t> bytes(data, size);
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::read_las_buffer(bytes, "fuzz.laz"); });
    return 0;
}
