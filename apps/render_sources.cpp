#include "apps/render_sources.hpp"

#include "config/species_library.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "render/colour_map.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace treelobes::cli {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
    return text;
}

std::vector<std::string> split_csv_line(const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream stream(line);
    std::string cell;
    while (std::getline(stream, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
}

std::vector<TileTree> read_trees_csv(const fs::path& file) {
    std::ifstream in(file);
    if (!in) throw Error::input(file.string(), "cannot open");
    std::string line;
    std::getline(in, line);
    const std::vector<std::string> header = split_csv_line(line);
    const auto column = [&](const std::string& name) {
        const auto it = std::find(header.begin(), header.end(), name);
        if (it == header.end()) throw Error::input(file.string(), "no '" + name + "' column (not a tile's trees.csv)");
        return static_cast<std::size_t>(it - header.begin());
    };
    const std::size_t id_column = column("tree_id"), species_column = column("species"), height_column = column("height_m");
    std::vector<TileTree> trees;
    for (int row = 2; std::getline(in, line); ++row) {
        if (line.empty()) continue;
        const std::vector<std::string> cells = split_csv_line(line);
        if (cells.size() != header.size())
            throw Error::input(file.string(), "line " + std::to_string(row) + ": " + std::to_string(cells.size()) + " cells, header has " +
                                                      std::to_string(header.size()));
        TileTree tree;
        try {
            tree.id = std::stoi(cells[id_column]);
            tree.height_m = cells[height_column].empty() ? std::nan("") : std::stod(cells[height_column]);
        } catch (const std::exception&) {
            throw Error::input(file.string(), "line " + std::to_string(row) + ": tree_id or height_m is not a number");
        }
        tree.species = cells[species_column];
        trees.push_back(tree);
    }
    std::sort(trees.begin(), trees.end(), [](const TileTree& a, const TileTree& b) { return a.id < b.id; });
    return trees;
}

std::uint64_t fnv1a(const std::string& text) {
    std::uint64_t hash = 14695981039346656037ull;
    for (unsigned char c : text) hash = (hash ^ c) * 1099511628211ull;
    return hash;
}

const std::vector<SpeciesEntry>& species_library() {
    static const std::vector<SpeciesEntry> entries = load_species_entries(default_species_file());
    return entries;
}

// Sorted names and, per point, the index of its name (-1: none), from a name per key and the
// key of each point.
PointSpecies index_names(const std::map<long long, std::string>& name_of_key, const std::vector<double>& key_of_point) {
    PointSpecies result;
    for (const auto& [key, name] : name_of_key) result.names.push_back(name);
    std::sort(result.names.begin(), result.names.end());
    result.names.erase(std::unique(result.names.begin(), result.names.end()), result.names.end());
    std::map<long long, int> index_of_key;
    for (const auto& [key, name] : name_of_key)
        index_of_key[key] = static_cast<int>(std::lower_bound(result.names.begin(), result.names.end(), name) - result.names.begin());
    result.of_point.reserve(key_of_point.size());
    for (double key : key_of_point) {
        const auto it = index_of_key.find(std::llround(key));
        result.of_point.push_back(it == index_of_key.end() ? -1 : it->second);
    }
    return result;
}

}  // namespace

bool is_tile_output(const fs::path& path) {
    return fs::is_directory(path) && fs::is_regular_file(path / "trees.csv") && fs::is_regular_file(path / "points.las");
}

TileOutput read_tile_output(const fs::path& dir) {
    if (!is_tile_output(dir)) throw Error::input(dir.string(), "not a tile output folder (needs trees.csv and points.las)");
    TileOutput tile;
    tile.trees = read_trees_csv(dir / "trees.csv");
    tile.points = read_point_cloud(dir / "points.las");
    if (!tree_id_attribute(tile.points)) throw Error::input((dir / "points.las").string(), "no treeID attribute");
    return tile;
}

const ExtraAttribute* tree_id_attribute(const PointCloud& cloud) {
    for (const auto& attribute : cloud.extras) {
        const std::string name = lower(attribute.name);
        if (name == "treeid" || name == "tree_id" || name == "scalar_treeid") return &attribute;
    }
    return nullptr;
}

PointSpecies point_species(const PointCloud& cloud, const std::vector<TileTree>* trees, const std::string& path) {
    std::map<long long, std::string> name_of_key;
    if (trees) {  // key: the tree id
        const ExtraAttribute* tree_id = tree_id_attribute(cloud);
        for (const auto& tree : *trees)
            if (!tree.species.empty()) name_of_key[tree.id] = tree.species;
        if (name_of_key.empty() || !tree_id)
            throw Error::input(path, "--color species: trees.csv names no species (run `treelobes tile` with --model)");
        return index_names(name_of_key, tree_id->values);
    }
    // key: the species id of config/species.yaml
    const auto attribute = std::find_if(cloud.extras.begin(), cloud.extras.end(), [](const ExtraAttribute& a) {
        return lower(a.name) == "species" || lower(a.name) == "scalar_species";
    });
    if (attribute == cloud.extras.end())
        throw Error::input(path,
                           "--color species needs a species attribute (LAS extra bytes or PLY scalar_species) or a tile output folder");
    std::map<long long, std::string> library_names;
    for (const auto& entry : species_library()) library_names[entry.id] = entry.name;
    for (double value : attribute->values) {
        const long long id = std::llround(value);
        if (id <= 0 || name_of_key.count(id)) continue;
        const auto it = library_names.find(id);
        name_of_key[id] = it != library_names.end() ? it->second : "species " + std::to_string(id);
    }
    return index_names(name_of_key, attribute->values);
}

render::Rgba species_colour(const std::string& name) {
    for (const auto& entry : species_library())
        if (lower(entry.name) == lower(name) || lower(entry.display_name) == lower(name)) return render::id_colour(entry.id);
    // Above the library's ids (1..255), so another name never takes a library species' colour.
    return render::id_colour(256 + static_cast<long long>(fnv1a(lower(name)) % 65536));
}

}  // namespace treelobes::cli
