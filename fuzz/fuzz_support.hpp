// Shared by the libFuzzer targets of fuzz/: the contract every reader must keep on any input.
//
// A reader may reject input only with treelobes::Error (the CLI turns it into one line and exit
// 2); any other exception, a crash, a sanitizer report, a hang or an allocation beyond
// libFuzzer's -malloc_limit_mb is a bug that the fuzzer reports.
#pragma once

#include "core/error.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <string_view>
#include <unistd.h>

namespace treelobes::fuzz {

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) { return {reinterpret_cast<const char*>(data), size}; }

// Runs `read` and swallows the one exception type that reports bad input.
template <typename Read>
void expect_only_input_errors(Read&& read) {
    try {
        read();
    } catch (const Error&) {}
}

// Readers that take a path get the input as a file with the extension that selects the
// format. One file per process (libFuzzer's -fork/-jobs run several), in memory when
// /dev/shm exists; the same path is reused for every input.
inline std::filesystem::path input_file(std::string_view bytes, const std::string& extension) {
    static const std::filesystem::path folder =
            std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
    const std::filesystem::path path = folder / ("treelobes-fuzz-" + std::to_string(::getpid()) + "." + extension);
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return path;
}

}  // namespace treelobes::fuzz
