// Shared helpers for the GoogleTest suite: where the real scans are, temporary folders,
// and running the CLI binary.
#pragma once

#include "core/error.hpp"

#include <filesystem>
#include <functional>
#include <string>

namespace treelobes::test {

// Folder of the real scans: $TREELOBES_REAL_DATA or ../shared/data beside the source tree.
// Fails the calling test (ADD_FAILURE + returns empty path) when it does not exist.
std::filesystem::path real_data_dir();
// real_data_dir() / relative; fails the test when the file is missing.
std::filesystem::path real_data(const std::string& relative);

// The source tree (for committed fixtures under data/ and tests/).
std::filesystem::path source_dir();

// A fresh, empty folder unique to the running test; removed by the destructor.
class TempDir {
public:
    TempDir();
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

private:
    std::filesystem::path path_;
};

struct CommandResult {
    int exit_code = -1;
    std::string out;  // stdout
    std::string err;  // stderr
};

// Runs build/bin/treelobes with the given argument string (shell-quoted by the caller).
CommandResult run_cli(const std::string& arguments);

// Exit code of the treelobes::Error that `action` throws; ExitCode::Ok when it throws none.
template <typename Action>
ExitCode error_code_of(Action&& action) {
    try {
        action();
    } catch (const Error& e) {
        return e.code();
    }
    return ExitCode::Ok;
}

// prefix + decimal i, e.g. numbered("t", 3) == "t3". Built by appending: GCC 12 warns falsely
// (-Wrestrict) on "t" + std::to_string(i) once it is inlined.
inline std::string numbered(std::string prefix, std::size_t i) {
    prefix += std::to_string(i);
    return prefix;
}

// A path in single quotes for run_cli's shell command line (paths of the tests have no quotes).
inline std::string quoted(const std::filesystem::path& path) {
    std::string text(1, '\'');
    text += path.string();
    text += '\'';
    return text;
}

// Writes text to a file (test fixtures).
void write_text(const std::filesystem::path& path, const std::string& text);

// A folder of data that the test processes of one ctest run share, made once by `make`.
// ctest runs every TEST in a process of its own, so a suite's expensive fixture (a synthetic
// survey and its batch run, say: 90 s under ASan) would otherwise be made again for each test.
// With TREELOBES_SHARED_FIXTURES set (ctest sets it for every test and empties the folder first,
// tests/CMakeLists.txt), the first process to ask makes <that folder>/<name> under a file lock
// and the others wait for it and reuse it; a make that failed its test is not reused. Without the
// variable (a test program run by hand) each process makes its own in a temporary folder.
std::filesystem::path shared_fixture(const std::string& name, const std::function<void(const std::filesystem::path&)>& make);

}  // namespace treelobes::test
