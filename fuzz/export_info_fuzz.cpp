// What `info` reads back from our exports (core/file_info.cpp): the glTF binary's header, chunks
// and JSON, and CityJSON documents. The first byte picks the extension.
#include "core/file_info.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::string extension = data[0] % 2 == 0 ? "glb" : "city.json";
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data + 1, size - 1), extension);
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::describe_file(path); });
    return 0;
}
