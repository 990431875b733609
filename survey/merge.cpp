#include "survey/merge.hpp"

#include "core/error.hpp"
#include "core/geojson.hpp"
#include "core/log.hpp"
#include "core/version.hpp"
#include "encode/forest_file.hpp"
#include "survey/completion.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
using nlohmann::json;

namespace treelobes::survey {

namespace {

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error::input(path.string(), "cannot open file");
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

// A tile's options without the flags that say where to read and write, whether to overwrite and
// how much memory a run may take (--out, --overwrite, --neighbours, --max-memory: they differ
// between a single run and shards on a cluster): the ones that shape what the tile holds, alike
// across the tiles of one survey.
json shaping_options(json options) {
    for (const char* key : {"out", "overwrite", "neighbours", "max_memory"}) options.erase(key);
    return options;
}

json read_json(const fs::path& path) {
    const json value = json::parse(read_text(path), nullptr, false);
    if (value.is_discarded() || !value.is_object()) throw Error::input(path.string(), "not a JSON object");
    return value;
}

bool is_tile_folder(const fs::path& dir) { return fs::is_regular_file(dir / "summary.json") && fs::is_regular_file(dir / "trees.csv"); }

std::string tile_of(const fs::path& dir) { return dir.filename().string(); }

long tree_id_of_name(const std::string& name, const std::string& context) {
    long id = 0;
    if (std::sscanf(name.c_str(), "tree_%ld", &id) != 1) throw Error::input(context, "forest tree '" + name + "' is not named tree_<id>");
    return id;
}

// The forest's tree options as the tile summary records them (options.trees).
encode::TreeFileOptions forest_options(const json& summary, const std::string& context) {
    encode::TreeFileOptions options;
    try {
        options.encode.resolution = summary.at("options").at("trees").at("dbf6_resolution").get<double>();
        options.lods = summary.at("options").at("trees").at("dbf6_lods").get<int>();
    } catch (const json::exception&) {
        throw Error::input(context, "summary.json without options.trees.dbf6_resolution / dbf6_lods (not a `treelobes tile` output)");
    }
    return options;
}

// Adds every number of `from` into `into`, recursing into objects (strings and the like are skipped).
void add_counts(json& into, const json& from) {
    for (const auto& [key, value] : from.items()) {
        if (value.is_number_integer())
            into[key] = into.value(key, 0L) + value.get<long>();
        else if (value.is_object()) {
            json& child = into[key];
            if (!child.is_object()) child = json::object();
            add_counts(child, value);
        }
    }
}

// A count of a tile's summary: 0 when absent. A number that is not an integer (1e30) is no
// count, and converting it as it is would be undefined: a damaged file.
long count_in(const json& counts, const char* key, const fs::path& file) {
    const auto it = counts.find(key);
    if (it == counts.end()) return 0;
    if (!it->is_number_integer()) throw Error::input(file.string(), std::string("count \"") + key + "\" is not an integer");
    return it->get<long>();
}

// A merged tree's key: its survey-wide id, then its tile (the same id in two tiles is one tree
// modelled twice, by tiles run without a buffer; both rows are kept and reported).
using TreeKey = std::pair<std::string, std::string>;

struct CsvRows {
    std::string header;                             // the tiles' header
    std::map<TreeKey, std::string> rows;            // by global id and tile
    std::map<TreeKey, std::string> global_of_tree;  // (tile, tile tree id) -> global id
};

constexpr const char* kGlobalIdColumn = "global_id,tree_id,";

void add_csv(CsvRows& all, const fs::path& tile_dir) {
    const std::string tile = tile_of(tile_dir);
    const fs::path path = tile_dir / "trees.csv";
    std::istringstream in(read_text(path));
    std::string header;
    std::getline(in, header);
    if (header.rfind(kGlobalIdColumn, 0) != 0)
        throw Error::input(path.string(), "no global_id column first (made by an older treelobes): run the tile again");
    if (all.header.empty())
        all.header = header;
    else if (header != all.header)
        throw Error::input(path.string(), "its columns differ from the other tiles'");
    for (std::string line; std::getline(in, line);) {
        if (line.empty()) continue;
        const std::size_t first = line.find(','), second = line.find(',', first + 1);
        if (first == std::string::npos || second == std::string::npos || first == 0)
            throw Error::input(path.string(), "a row without its ids");
        const std::string global = line.substr(0, first), tree = line.substr(first + 1, second - first - 1);
        all.rows[{global, tile}] = global + "," + tile + line.substr(first) + "\n";
        all.global_of_tree[{tile, tree}] = global;
    }
}

// The ids found in more than one tile, each with its tiles ("id in a, b").
std::vector<std::string> duplicated_ids(const CsvRows& csv) {
    std::map<std::string, std::vector<std::string>> tiles_of;
    for (const auto& [key, row] : csv.rows) tiles_of[key.first].push_back(key.second);
    std::vector<std::string> duplicated;
    for (const auto& [id, tiles] : tiles_of) {
        if (tiles.size() < 2) continue;
        std::string text = id + " in";
        for (std::size_t i = 0; i < tiles.size(); ++i) text += (i ? ", " : " ") + tiles[i];
        duplicated.push_back(text);
    }
    return duplicated;
}

// The features of the tile's `file` (trees.geojson, crowns.geojson), each with its tile's name.
void add_features(std::map<TreeKey, json>& features, std::string& crs, const fs::path& tile_dir, const char* file) {
    const std::string tile = tile_of(tile_dir);
    const fs::path path = tile_dir / file;
    if (!fs::exists(path)) throw Error::input(path.string(), "missing (a tile made by an older treelobes): run the tile again");
    const json collection = read_json(path);
    const std::string tile_crs = collection.value("crs_wkt", std::string());
    if (!tile_crs.empty()) {
        if (!crs.empty() && crs != tile_crs) throw Error::input(path.string(), "its CRS differs from the other tiles'");
        crs = tile_crs;
    }
    for (json feature : collection.at("features")) {
        const std::string global = feature.at("properties").at("global_id").get<std::string>();
        feature["properties"]["tile"] = tile;
        features[{global, tile}] = std::move(feature);
    }
}

// The features in the order of their keys (the survey-wide tree id), as one collection.
std::string sorted_collection(std::map<TreeKey, json>& features, const std::string& crs) {
    json sorted = json::array();
    for (auto& [id, feature] : features) sorted.push_back(std::move(feature));
    return feature_collection(std::move(sorted), crs);
}

// The tile's forest trees, placed as `treelobes tile` places them (root at the position).
void add_forest_trees(std::map<TreeKey, encode::ForestTree>& trees, const CsvRows& csv, const fs::path& tile_dir) {
    const std::string tile = tile_of(tile_dir);
    const fs::path path = tile_dir / "tile.forest";
    encode::ForestReader reader(path);
    for (std::size_t i = 0; i < reader.size(); ++i) {
        const std::string tree = std::to_string(tree_id_of_name(reader.entry(i).name, path.string()));
        const auto global_of = csv.global_of_tree.find({tile, tree});
        if (global_of == csv.global_of_tree.end()) throw Error::input(path.string(), "tree_" + tree + " is not in the tile's trees.csv");
        const std::string& global = global_of->second;
        encode::ForestTree placed;
        placed.skeleton = reader.decode(i, 0);
        const Eigen::Vector3d root = placed.skeleton.origin + placed.skeleton.nodes.at(0).position.cast<double>();
        placed.skeleton.origin = -placed.skeleton.nodes[0].position.cast<double>();
        placed.position = root;
        placed.name = global;
        trees[{global, tile}] = std::move(placed);
    }
}

std::string failure_lines(const std::vector<fs::path>& lists) {
    std::set<std::string> lines;
    for (const fs::path& list : lists) {
        std::istringstream in(read_text(list));
        for (std::string line; std::getline(in, line);)
            if (!line.empty()) lines.insert(line);
    }
    std::string text;
    for (const std::string& line : lines) text += line + "\n";
    return text;
}

}  // namespace

TileFolders find_tile_folders(const std::vector<fs::path>& dirs) {
    TileFolders found;
    std::map<std::string, fs::path> by_name;
    const auto add = [&](const fs::path& dir) {
        const auto [it, fresh] = by_name.emplace(tile_of(dir), dir);
        if (!fresh)
            throw Error::input(dir.string(), "tile '" + it->first + "' is also in " + it->second.string() + ": merge each tile once");
    };
    std::set<std::string> incomplete;
    for (const fs::path& dir : dirs) {
        if (!fs::is_directory(dir)) throw Error::input(dir.string(), "no such folder");
        if (is_tile_folder(dir)) {
            add(dir);
            continue;
        }
        for (const auto& entry : fs::directory_iterator(dir)) {
            if (entry.is_regular_file() && entry.path().filename().string().rfind("failures", 0) == 0 &&
                entry.path().extension() == ".jsonl")
                found.failure_lists.push_back(entry.path());
            if (!entry.is_directory()) continue;
            if (fs::is_regular_file(entry.path() / kCompletionMarker) && is_tile_folder(entry.path()))
                add(entry.path());
            else
                incomplete.insert(tile_of(entry.path()));
        }
    }
    for (const auto& [name, dir] : by_name) {
        found.complete.push_back(dir);
        incomplete.erase(name);  // finished in another batch folder
    }
    found.incomplete.assign(incomplete.begin(), incomplete.end());
    std::sort(found.failure_lists.begin(), found.failure_lists.end());
    return found;
}

MergedSurvey merge_tiles(const TileFolders& folders) {
    if (folders.complete.empty()) throw Error::input("merge", "no finished tiles in the given folders");
    MergedSurvey merged;
    CsvRows csv;
    std::map<TreeKey, json> features, crowns;
    std::map<TreeKey, encode::ForestTree> forest_trees;
    std::string crs;
    json counts = json::object();
    json tiles = json::array();
    json options;
    std::optional<encode::TreeFileOptions> dbf6;
    for (const fs::path& dir : folders.complete) {  // sorted by tile name
        try {
            const json summary = read_json(dir / "summary.json");
            const encode::TreeFileOptions tile_dbf6 = forest_options(summary, (dir / "summary.json").string());
            if (dbf6 && (tile_dbf6.encode.resolution != dbf6->encode.resolution || tile_dbf6.lods != dbf6->lods))
                throw Error::input((dir / "summary.json").string(),
                                   "made with other DBF6 options (--resolution, --lods) than the other tiles");
            dbf6 = tile_dbf6;
            const json tile_options = shaping_options(summary.at("options"));
            if (options.is_null())
                options = tile_options;
            else if (options != tile_options)
                log_warn(dir.string() + ": made with other tile options than " + folders.complete.front().string());
            if (const auto buffer = summary.find("buffer"); buffer != summary.end() && buffer->is_object())
                for (const json& id : buffer->value("trees_at_edge", json::array()))
                    merged.trees_at_buffer_edge.push_back(id.get<std::string>());
            json tile_counts = summary.at("counts");
            tile_counts.erase("trees_reused");  // how a tile was resumed, not what it holds
            add_counts(counts, tile_counts);
            tiles.push_back({{"name", tile_of(dir)},
                             {"trees", count_in(tile_counts, "trees", dir / "summary.json")},
                             {"trees_failed", count_in(tile_counts, "trees_failed", dir / "summary.json")}});
            add_csv(csv, dir);
            add_features(features, crs, dir, "trees.geojson");
            add_features(crowns, crs, dir, "crowns.geojson");
            add_forest_trees(forest_trees, csv, dir);
        } catch (const json::exception& e) {
            // Files that parse but miss a field or hold one of another type: the tile's outputs
            // were damaged (edited, or written by another program); say which tile, not where in nlohmann.
            throw Error::input(dir.string(), std::string("malformed tile outputs (") + e.what() + ")");
        }
    }
    merged.tiles = folders.complete.size();
    merged.trees = csv.rows.size();
    merged.duplicated_ids = duplicated_ids(csv);
    std::sort(merged.trees_at_buffer_edge.begin(), merged.trees_at_buffer_edge.end());
    merged.trees_csv = "global_id,tile," + csv.header.substr(std::string("global_id,").size()) + "\n";
    for (const auto& [id, row] : csv.rows) merged.trees_csv += row;
    merged.trees_geojson = sorted_collection(features, crs);
    merged.crowns_geojson = sorted_collection(crowns, crs);
    std::vector<encode::ForestTree> ordered;
    ordered.reserve(forest_trees.size());
    for (auto& [id, tree] : forest_trees) ordered.push_back(std::move(tree));
    merged.forest = encode::write_forest_bytes(ordered, *dbf6);
    merged.failures_jsonl = failure_lines(folders.failure_lists);
    const json summary = {{"treelobes", kVersion},
                          {"command", "merge"},
                          {"counts", counts},
                          {"tiles", tiles},
                          {"tiles_merged", merged.tiles},
                          {"tiles_incomplete", folders.incomplete},
                          {"tiles_failed", std::count(merged.failures_jsonl.begin(), merged.failures_jsonl.end(), '\n')},
                          {"trees", merged.trees},
                          {"trees_in_several_tiles", merged.duplicated_ids.size()},
                          {"trees_at_buffer_edge", merged.trees_at_buffer_edge},
                          {"forest_trees", ordered.size()},
                          {"crs", crs.empty() ? json(nullptr) : json(crs)},
                          {"options", options}};
    merged.summary_json = summary.dump(2) + "\n";
    return merged;
}

}  // namespace treelobes::survey
