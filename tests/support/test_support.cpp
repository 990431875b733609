#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <fcntl.h>
#include <sys/file.h>
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

namespace {

// An exclusive flock on a file, released (with the file closed) by the destructor.
class FileLock {
public:
    explicit FileLock(const fs::path& path) : fd_(::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644)) {
        if (fd_ < 0 || ::flock(fd_, LOCK_EX) != 0) throw std::runtime_error("cannot lock " + path.string());
    }
    ~FileLock() { ::close(fd_); }
    FileLock(const FileLock&) = delete;
    FileLock& operator=(const FileLock&) = delete;

private:
    int fd_;
};

}  // namespace

fs::path shared_fixture(const std::string& name, const std::function<void(const fs::path&)>& make) {
    const char* root = std::getenv("TREELOBES_SHARED_FIXTURES");
    if (!root || !*root) {
        static std::vector<std::unique_ptr<TempDir>> own;  // removed when the process ends
        own.push_back(std::make_unique<TempDir>());
        const fs::path dir = own.back()->path() / name;
        fs::create_directories(dir);
        make(dir);
        return dir;
    }
    const fs::path dir = fs::path(root) / name;
    fs::create_directories(root);
    const FileLock lock(fs::path(root) / (name + ".lock"));
    const fs::path made = dir / ".made";
    if (!fs::exists(made)) {
        fs::remove_all(dir);
        fs::create_directories(dir);
        make(dir);
        if (!::testing::Test::HasFailure()) write_text(made, "");
    }
    return dir;
}

}  // namespace treelobes::test
