#include "core/atomic_file.hpp"

#include "core/error.hpp"

#include <fstream>
#include <sstream>
#include <system_error>
#include <unistd.h>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

fs::path temporary_path_for(const fs::path& path) { return fs::path(path.string() + ".tmp." + std::to_string(::getpid())); }

void check_destination(const fs::path& path) {
    if (path.empty()) throw Error::usage("output path is empty");
    if (fs::is_directory(path)) throw Error::input(path.string(), "is a directory, expected a file path to write");
    const fs::path parent = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    if (!fs::is_directory(parent)) throw Error::input(path.string(), "cannot write: folder " + parent.string() + " does not exist");
}

// Runs `produce` to create `temporary`, then renames it onto `path`; on any failure the
// temporary is removed and the destination is left as it was.
void replace_with(const fs::path& path, const fs::path& temporary, const std::function<void()>& produce) {
    try {
        produce();
        if (!fs::exists(temporary)) throw Error::input(path.string(), "cannot write (permission denied or read-only folder)");
        std::error_code ec;
        fs::rename(temporary, path, ec);
        if (ec) throw Error::input(path.string(), "cannot replace file: " + ec.message());
    } catch (...) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        throw;
    }
}

}  // namespace

void write_atomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
    check_destination(path);
    const fs::path temporary = temporary_path_for(path);
    replace_with(path, temporary, [&] {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) throw Error::input(path.string(), "cannot write (permission denied or read-only folder)");
        write(out);
        out.flush();
        if (!out) throw Error::input(path.string(), "write failed (disk full?)");
    });
}

void write_atomically_via_path(const fs::path& path, const std::function<void(const fs::path&)>& write) {
    check_destination(path);
    // Keep the extension last: these libraries pick the format from it.
    const fs::path temporary =
            path.parent_path() / (path.stem().string() + ".tmp." + std::to_string(::getpid()) + path.extension().string());
    replace_with(path, temporary, [&] { write(temporary); });
}

void write_file_atomically(const fs::path& path, const std::string& contents) {
    write_atomically(path, [&](std::ostream& out) { out.write(contents.data(), static_cast<std::streamsize>(contents.size())); });
}

std::string read_file(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error::input(path.string(), "no such file");
    if (fs::is_directory(path, ec)) throw Error::input(path.string(), "is a directory, expected a file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error::input(path.string(), "cannot open for reading (permission denied?)");
    std::ostringstream buffer;
    buffer << in.rdbuf();
    if (in.bad()) throw Error::input(path.string(), "read error");
    return buffer.str();
}

}  // namespace treelobes
