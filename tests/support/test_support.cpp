#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace treelobes::test {

fs::path real_data_dir() {
    const char* env = std::getenv("TREELOBES_REAL_DATA");
    fs::path dir = env && *env ? fs::path(env) : fs::path(TREELOBES_DEFAULT_REAL_DATA);
    if (!fs::is_directory(dir)) {
        ADD_FAILURE() << "real scan folder not found: " << dir << " (set TREELOBES_REAL_DATA to the folder of ../shared/data)";
        return {};
    }
    return dir;
}

fs::path real_data(const std::string& relative) {
    fs::path dir = real_data_dir();
    if (dir.empty()) return {};
    fs::path file = dir / relative;
    if (!fs::exists(file)) ADD_FAILURE() << "real scan missing: " << file;
    return file;
}

fs::path source_dir() { return fs::path(TREELOBES_SOURCE_DIR); }

TempDir::TempDir() {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "_" + info->name() : "test";
    for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    path_ = fs::temp_directory_path() / ("treelobes_" + name + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
}

TempDir::~TempDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
}

static std::string slurp(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

CommandResult run_cli(const std::string& arguments) {
    TempDir scratch;
    const fs::path out = scratch / "stdout", err = scratch / "stderr";
    const std::string command =
            std::string("'") + TREELOBES_CLI + "' " + arguments + " >'" + out.string() + "' 2>'" + err.string() + "' </dev/null";
    const int status = std::system(command.c_str());
    CommandResult result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    result.out = slurp(out);
    result.err = slurp(err);
    return result;
}

void write_text(const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
}

}  // namespace treelobes::test
