#include "survey/completion.hpp"

#include "core/atomic_file.hpp"

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace treelobes::survey {

namespace {

nlohmann::json read_marker(const fs::path& tile_dir) {
    std::ifstream in(tile_dir / kCompletionMarker);
    if (!in) return nullptr;
    std::ostringstream text;
    text << in.rdbuf();
    const auto marker = nlohmann::json::parse(text.str(), nullptr, false);
    return marker.is_object() ? marker : nlohmann::json(nullptr);
}

}  // namespace

void mark_complete(const fs::path& tile_dir, const std::string& key, int exit_code) {
    const nlohmann::json marker = {{"key", key}, {"exit_code", exit_code}};
    write_file_atomically(tile_dir / kCompletionMarker, marker.dump() + "\n");
}

bool is_complete(const fs::path& tile_dir, const std::string& key) {
    const auto marker = read_marker(tile_dir);
    return !marker.is_null() && marker.value("key", std::string()) == key;
}

int completed_exit_code(const fs::path& tile_dir) {
    const auto marker = read_marker(tile_dir);
    return marker.is_null() ? -1 : marker.value("exit_code", -1);
}

}  // namespace treelobes::survey
