// QSM tables (core/qsm_io.cpp): the TreeQSM cylinder text and the SimpleForest/rTwig CSV. The
// first byte picks the extension, so one corpus covers both.
#include "core/qsm_io.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::string extension = data[0] % 2 == 0 ? "txt" : "csv";
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data + 1, size - 1), extension);
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::read_qsm(path); });
    return 0;
}
