#include "survey/tile_list.hpp"

#include "core/cloud_io.hpp"
#include "core/error.hpp"

#include <glob.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <map>
#include <set>

namespace fs = std::filesystem;

namespace treelobes::survey {

namespace {

bool is_point_cloud_file(const fs::path& path) {
    static const std::set<std::string> extensions{"las", "laz", "ply", "pcd", "xyz", "csv", "pts", "asc"};
    return extensions.count(file_extension(path)) > 0;
}

std::vector<fs::path> folder_tiles(const fs::path& folder) {
    std::vector<fs::path> tiles;
    for (const auto& entry : fs::directory_iterator(folder))
        if (entry.is_regular_file() && is_point_cloud_file(entry.path())) tiles.push_back(entry.path());
    return tiles;
}

std::vector<fs::path> pattern_tiles(const std::string& pattern) {
    glob_t found{};
    const int status = glob(pattern.c_str(), 0, nullptr, &found);
    std::vector<fs::path> tiles;
    if (status == 0)
        for (std::size_t i = 0; i < found.gl_pathc; ++i)
            if (fs::is_regular_file(found.gl_pathv[i])) tiles.emplace_back(found.gl_pathv[i]);
    globfree(&found);
    return tiles;
}

std::vector<fs::path> listed_tiles(const fs::path& list) {
    std::ifstream in(list);
    if (!in) throw Error::input(list.string(), "cannot open the tile list");
    std::vector<fs::path> tiles;
    std::size_t line_number = 0;
    for (std::string line; std::getline(in, line);) {
        ++line_number;
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
        const auto first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        fs::path tile = line.substr(first);
        if (tile.is_relative()) tile = list.parent_path() / tile;
        if (!fs::is_regular_file(tile))
            throw Error::input(list.string(), "line " + std::to_string(line_number) + ": " + tile.string() + " is not a file");
        tiles.push_back(tile.lexically_normal());
    }
    return tiles;
}

}  // namespace

std::string tile_name(const fs::path& tile) { return tile.stem().string(); }

std::vector<fs::path> list_tiles(const std::string& source) {
    std::vector<fs::path> tiles;
    if (source.find_first_of("*?[") != std::string::npos) {
        tiles = pattern_tiles(source);
    } else if (fs::is_directory(source)) {
        tiles = folder_tiles(source);
    } else if (fs::is_regular_file(source)) {
        tiles = is_point_cloud_file(source) ? std::vector<fs::path>{source} : listed_tiles(source);
    } else {
        throw Error::input(source, "no such file, folder or pattern of tiles");
    }
    if (tiles.empty()) throw Error::input(source, "no tiles found (.las .ply .pcd .xyz .csv .pts .asc)");
    std::sort(tiles.begin(), tiles.end(), [](const fs::path& a, const fs::path& b) { return a.string() < b.string(); });
    tiles.erase(std::unique(tiles.begin(), tiles.end()), tiles.end());
    std::map<std::string, fs::path> by_name;
    for (const fs::path& tile : tiles) {
        const auto [it, fresh] = by_name.emplace(tile_name(tile), tile);
        if (!fresh)
            throw Error::usage(source + ": " + it->second.string() + " and " + tile.string() + " have the same name '" + it->first +
                               "' (one output folder per name): rename one of them");
    }
    return tiles;
}

Shard parse_shard(const std::string& text) {
    Shard shard;
    const auto slash = text.find('/');
    const auto number = [&](std::string_view part, std::size_t& value) {
        const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
        return ec == std::errc() && end == part.data() + part.size() && !part.empty();
    };
    const std::string_view all(text);
    if (slash == std::string::npos || !number(all.substr(0, slash), shard.index) || !number(all.substr(slash + 1), shard.count) ||
        shard.count == 0 || shard.index >= shard.count)
        throw Error::usage("--shard " + text + ": expected i/n with 0 <= i < n (e.g. $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT)");
    return shard;
}

std::vector<fs::path> shard_tiles(const std::vector<fs::path>& tiles, const Shard& shard) {
    std::vector<fs::path> mine;
    for (std::size_t i = shard.index; i < tiles.size(); i += shard.count) mine.push_back(tiles[i]);
    return mine;
}

}  // namespace treelobes::survey
