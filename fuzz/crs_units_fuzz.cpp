// The CRS unit readers (core/crs_units.cpp, horizontal and vertical) on any text: the WKT of a LAS file's VLR is untrusted
// input, up to 64 kB (an EVLR more), read for every tile.
#include "core/crs_units.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text = treelobes::fuzz::as_text(data, size);
    const auto unit = treelobes::crs_horizontal_unit(text);
    if (unit && !unit->angular && !(unit->metres > 0.0)) __builtin_trap();  // a length unit has a size
    const auto vertical = treelobes::crs_vertical_unit(text);
    if (vertical && (vertical->angular || !(vertical->metres > 0.0))) __builtin_trap();  // heights have a length unit
    return 0;
}
