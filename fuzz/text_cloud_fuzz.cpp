// Delimited text clouds (.xyz .txt .csv .pts .asc): delimiters, header lines, extra columns.
#include "core/cloud_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data, size), "csv");
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::read_text_cloud(path); });
    return 0;
}
