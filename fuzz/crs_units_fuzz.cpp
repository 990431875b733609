// The CRS unit reader (core/crs_units.cpp) on any text: the WKT of a LAS file's VLR is untrusted
// input, up to 64 kB (an EVLR more), read for every tile.
#include "core/crs_units.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto unit = treelobes::crs_horizontal_unit(treelobes::fuzz::as_text(data, size));
    if (unit && !unit->angular && !(unit->metres > 0.0)) __builtin_trap();  // a length unit has a size
    return 0;
}
