// `treelobes encode`, `lod`, `decode` and `decode-code`: F6/DBF6 chain codes of skeletons
// (Strnad et al. 2020, §3.1-3.2) on the command line. Without --out, codes and radius lists travel as text
// (the code on one line, the comma-separated radii on the next); with --out they are compressed
// into a .dbf6 file (one tree, LODs) or a .forest file (many trees), which `decode` reads back
// (Strnad et al. 2020, §3.3, §4; docs/dbf6.md, docs/forest.md).
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/skeleton_io.hpp"
#include "core/version.hpp"
#include "core/atomic_file.hpp"
#include "encode/chain_code.hpp"
#include "encode/forest_file.hpp"
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"
#include "encode/tree_file.hpp"
#include "lobes/tlobe_io.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

namespace treelobes::cli {

namespace {

using namespace treelobes::encode;

namespace fs = std::filesystem;

struct EncodeCliOptions {
    std::string skeleton;
    std::string forest;  // directory of skeletons or a list file
    std::string out;     // .dbf6 (one tree) or .forest (--forest)
    double resolution = 5.0;
    std::string internode_length = "auto";
    double radius_unit = 0.001;
    bool f6 = false;
    bool print_code = false;
    int lods = 1;
    std::string coder = "best";
    bool stats = false;
    // Given on the command line (otherwise a decoded skeleton's recorded values apply).
    bool resolution_given = false, internode_length_given = false, radius_unit_given = false;
};

struct DecodeFileCliOptions {
    std::string input;
    int lod = 0;
    int tree = -1;  // -1: every tree of a forest
    std::string out;
    bool ascii = false;
    bool stats = false;
};

struct LodCliOptions {
    std::string code;
    std::string radii;
    double threshold = 0.0;
    int levels = 0;
};

struct DecodeCliOptions {
    std::string code;
    std::string radii;
    double resolution = 5.0;
    double internode_length = 0.0;
    double radius_unit = 0.001;
    int root_radius = -1;  // -1: the first internode's radius
    bool f6 = false;
    bool ascii = false;
    std::string out;
};

std::string join_radii(const std::vector<int>& radii) {
    std::string text;
    for (std::size_t i = 0; i < radii.size(); ++i) text += (i ? "," : "") + std::to_string(radii[i]);
    return text;
}

// "auto" -> 0 (median edge length), otherwise a positive length in metres.
double parse_internode_length(const std::string& text) {
    if (text == "auto") return 0.0;
    double value = 0.0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size() || !(value > 0.0) || !std::isfinite(value))
        throw Error::usage("--internode-length must be 'auto' or a positive length in metres (got '" + text + "')");
    return value;
}

// Options given on the command line win; otherwise the parameters a decoded skeleton recorded
// (so encode -> decode -> encode reproduces the code), otherwise the defaults.
EncodeOptions encode_options_of(const EncodeCliOptions& options, const std::optional<CodeParameters>& recorded = {}) {
    EncodeOptions encode_options;
    if (!options.resolution_given && !recorded)
        throw Error::usage("--resolution is required: " + options.skeleton + " records no chain-code resolution");
    encode_options.resolution = options.resolution_given ? options.resolution : recorded->resolution;
    encode_options.internode_length =
            options.internode_length_given || !recorded ? parse_internode_length(options.internode_length) : recorded->internode_length;
    encode_options.radius_unit = options.radius_unit_given || !recorded ? options.radius_unit : recorded->radius_unit;
    encode_options.kind = options.f6 ? CodeKind::F6 : CodeKind::DBF6;
    return encode_options;
}

TreeFileOptions file_options_of(const EncodeCliOptions& options, const std::optional<CodeParameters>& recorded = {}) {
    TreeFileOptions file_options;
    file_options.encode = encode_options_of(options, recorded);
    file_options.lods = options.lods;
    file_options.coder = parse_coder(options.coder);
    return file_options;
}

bool has_extension(const fs::path& path, const std::string& extension) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return ext == extension;
}

// A skeleton PLY, or the main skeleton of a lobe-based tree (.tlobe). `recorded` receives the
// chain-code parameters a decoded skeleton PLY records.
TreeGraph read_tree_input(const fs::path& path, std::optional<CodeParameters>* recorded = nullptr) {
    if (has_extension(path, ".tlobe")) return lobes::read_tlobe(path).skeleton;
    std::vector<std::string> comments;
    TreeGraph tree = read_skeleton_ply(path, &comments);
    if (recorded) *recorded = find_code_parameters(comments, path.string());
    return tree;
}

nlohmann::json lod_stats_json(const StoredTree& tree, const std::vector<StreamSizes>& sizes) {
    nlohmann::json lods = nlohmann::json::array();
    for (std::size_t k = 0; k < sizes.size(); ++k) {
        nlohmann::json lod = {{"lod", k},
                              {"threshold", k ? tree.thresholds[k - 1] : 0},
                              {"symbol_bytes", sizes[k].symbols},
                              {"radii_bytes", sizes[k].radii}};
        if (!tree.lods[k].radii.empty() || sizes[k].internodes) {  // counts only for LODs that were decoded
            lod["internodes"] = sizes[k].internodes;
            lod["code_length"] = sizes[k].code_length;
        }
        lods.push_back(lod);
    }
    return lods;
}

void print_lod_stats(const StoredTree& tree, const std::vector<StreamSizes>& sizes) {
    for (std::size_t k = 0; k < sizes.size(); ++k) {
        std::cout << "  LOD " << k;
        if (k) std::cout << " (threshold " << tree.thresholds[k - 1] << ")";
        std::cout << ": ";
        if (!tree.lods[k].radii.empty() || sizes[k].internodes)
            std::cout << sizes[k].internodes << " internodes, " << sizes[k].code_length << " symbols -> ";
        std::cout << sizes[k].symbols << " + " << sizes[k].radii << " bytes (symbols + radii)\n";
    }
}

int run_encode_file(const EncodeCliOptions& options, const OptionTable& table, const GlobalOptions& global) {
    std::optional<CodeParameters> recorded;
    const TreeGraph tree = read_tree_input(options.skeleton, &recorded);
    const StoredTree stored = store_tree(tree, file_options_of(options, recorded), options.skeleton);
    std::vector<StreamSizes> sizes;
    const std::vector<std::uint8_t> bytes = write_tree_file_bytes(stored, &sizes);
    write_file_atomically(options.out, std::string(bytes.begin(), bytes.end()));
    const std::size_t internodes = stored.lods[0].radii.size();
    const std::size_t raw = 16 * internodes;  // Strnad et al. 2020, Table 5: 16 bytes per internode
    if (global.json) {
        nlohmann::json j = {{"treelobes", kVersion},
                            {"options", table.json()},
                            {"input", options.skeleton},
                            {"out", options.out},
                            {"kind", code_kind_name(stored.kind)},
                            {"coder", coder_name(stored.coder)},
                            {"resolution", stored.resolution},
                            {"internode_length", stored.internode_length},
                            {"radius_unit", stored.radius_unit},
                            {"root_radius", stored.root_radius},
                            {"internodes", internodes},
                            {"file_bytes", bytes.size()},
                            {"raw_bytes", raw}};
        if (options.stats) j["lods"] = lod_stats_json(stored, sizes);
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::cout << "wrote " << options.out << ": " << bytes.size() << " bytes for " << internodes << " internodes ("
              << coder_name(stored.coder) << " coder, " << stored.lods.size() << " LOD" << (stored.lods.size() > 1 ? "s" : "") << ", "
              << static_cast<double>(raw) / static_cast<double>(bytes.size()) << "x smaller than 16 bytes per internode)\n";
    if (options.stats) print_lod_stats(stored, sizes);
    return 0;
}

// Trees of a forest: every skeleton PLY / .tlobe in a directory (sorted by name), or a list file
// with one tree per line: `PATH [X Y Z [AZIMUTH_DEGREES]]` (relative paths from the list's folder,
// # comments). Without a position a tree stands where its skeleton's root is.
std::vector<ForestTree> read_forest_input(const fs::path& input) {
    struct Item {
        fs::path path;
        bool placed = false;
        Eigen::Vector3d position{0, 0, 0};
        double azimuth_degrees = 0.0;
    };
    std::vector<Item> items;
    if (fs::is_directory(input)) {
        for (const auto& entry : fs::directory_iterator(input))
            if (entry.is_regular_file() && (has_extension(entry.path(), ".ply") || has_extension(entry.path(), ".tlobe")))
                items.push_back({entry.path()});
        std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) { return a.path < b.path; });
        if (items.empty()) throw Error::input(input.string(), "no skeleton .ply or .tlobe files in the directory");
    } else {
        std::istringstream list(read_file(input));
        std::string line;
        for (int number = 1; std::getline(list, line); ++number) {
            const auto hash = line.find('#');
            if (hash != std::string::npos) line.erase(hash);
            std::istringstream fields(line);
            std::vector<std::string> tokens;
            for (std::string token; fields >> token;) tokens.push_back(token);
            if (tokens.empty()) continue;
            const std::string where = "line " + std::to_string(number);
            if (tokens.size() != 1 && tokens.size() != 4 && tokens.size() != 5)
                throw Error::input(input.string(), where + ": expected PATH [X Y Z [AZIMUTH_DEGREES]]");
            Item item{fs::path(tokens[0]).is_absolute() ? fs::path(tokens[0]) : input.parent_path() / tokens[0]};
            std::vector<double> numbers;
            for (std::size_t t = 1; t < tokens.size(); ++t) {
                double value = 0.0;
                const auto [end, error] = std::from_chars(tokens[t].data(), tokens[t].data() + tokens[t].size(), value);
                if (error != std::errc() || end != tokens[t].data() + tokens[t].size() || !std::isfinite(value))
                    throw Error::input(input.string(), where + ": '" + tokens[t] + "' is not a finite number");
                numbers.push_back(value);
            }
            if (numbers.size() >= 3) {
                item.placed = true;
                item.position = {numbers[0], numbers[1], numbers[2]};
            }
            if (numbers.size() == 4) item.azimuth_degrees = numbers[3];
            items.push_back(item);
        }
        if (items.empty()) throw Error::input(input.string(), "the tree list names no trees");
    }
    std::vector<ForestTree> trees;
    for (const Item& item : items) {
        ForestTree tree;
        tree.skeleton = read_tree_input(item.path);
        tree.skeleton.validate(item.path.string());
        tree.name = item.path.stem().string();
        // Store the tree in its own frame with the root at 0; its placement goes to the index.
        const Eigen::Vector3d root = tree.skeleton.origin + tree.skeleton.nodes[0].position.cast<double>();
        tree.skeleton.origin = -tree.skeleton.nodes[0].position.cast<double>();
        tree.position = item.placed ? item.position : root;
        tree.azimuth = static_cast<float>(item.azimuth_degrees * M_PI / 180.0);
        trees.push_back(std::move(tree));
    }
    return trees;
}

int run_encode_forest(const EncodeCliOptions& options, const OptionTable& table, const GlobalOptions& global) {
    const std::vector<ForestTree> trees = read_forest_input(options.forest);
    ForestStats stats;
    const std::vector<std::uint8_t> bytes = write_forest_bytes(trees, file_options_of(options), &stats);
    write_file_atomically(options.out, std::string(bytes.begin(), bytes.end()));
    std::size_t internodes = 0;
    for (const auto& tree : stats.trees) internodes += tree.empty() ? 0 : tree[0].internodes;
    if (global.json) {
        nlohmann::json j = {{"treelobes", kVersion},      {"options", table.json()},      {"input", options.forest},
                            {"out", options.out},         {"trees", trees.size()},        {"internodes", internodes},
                            {"file_bytes", bytes.size()}, {"raw_bytes", 16 * internodes}, {"index_bytes", stats.header_and_index},
                            {"coder", options.coder},     {"lods", options.lods},         {"resolution", options.resolution}};
        if (options.stats) {
            j["tree_stats"] = nlohmann::json::array();
            for (std::size_t i = 0; i < trees.size(); ++i) {
                nlohmann::json lods = nlohmann::json::array();
                for (std::size_t k = 0; k < stats.trees[i].size(); ++k)
                    lods.push_back({{"lod", k},
                                    {"internodes", stats.trees[i][k].internodes},
                                    {"symbol_bytes", stats.trees[i][k].symbols},
                                    {"radii_bytes", stats.trees[i][k].radii}});
                j["tree_stats"].push_back({{"name", trees[i].name}, {"lods", lods}});
            }
        }
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::cout << "wrote " << options.out << ": " << trees.size() << " trees, " << internodes << " internodes, " << bytes.size()
              << " bytes (header and index " << stats.header_and_index << ")\n";
    if (options.stats)
        for (std::size_t i = 0; i < trees.size(); ++i) {
            std::size_t total = 0;
            for (const StreamSizes& s : stats.trees[i]) total += s.symbols + s.radii;
            std::cout << "  " << i << " " << trees[i].name << ": " << stats.trees[i][0].internodes << " internodes, " << total
                      << " bytes of streams\n";
        }
    return 0;
}

int run_encode(const EncodeCliOptions& options, const OptionTable& table, const GlobalOptions& global) {
    if (!options.forest.empty()) return run_encode_forest(options, table, global);
    if (!options.out.empty()) return run_encode_file(options, table, global);
    std::optional<CodeParameters> recorded;
    const TreeGraph tree = read_tree_input(options.skeleton, &recorded);
    const EncodeOptions encode_options = encode_options_of(options, recorded);
    const EncodedTree encoded = encode_tree(tree, encode_options, options.skeleton);

    const SymbolCounts counts = count_symbols(encoded.code.symbols);
    const std::size_t f6_length = write_symbols(encoded.internodes, CodeKind::F6).size();
    const std::size_t dbf6_length = write_symbols(encoded.internodes, CodeKind::DBF6).size();
    const double bound = std::sqrt(3.0) * encoded.geometry.voxel_size / 2.0;
    if (global.json) {
        nlohmann::json j = {{"treelobes", kVersion},
                            {"options", table.json()},
                            {"input", options.skeleton},
                            {"kind", code_kind_name(encode_options.kind)},
                            {"resolution", encoded.resolution},
                            {"internode_length", encoded.internode_length},
                            {"internode_length_auto", encode_options.internode_length == 0.0},
                            {"voxel_size", encoded.geometry.voxel_size},
                            {"error_bound", bound},
                            {"radius_unit", encoded.geometry.radius_unit},
                            {"root_radius", encoded.geometry.root_radius},
                            {"nodes", tree.size()},
                            {"internodes", counts.internodes},
                            {"forks", counts.forks},
                            {"tips", counts.tips},
                            {"code_length", encoded.code.symbols.size()},
                            {"f6_length", f6_length},
                            {"dbf6_length", dbf6_length},
                            {"code", encoded.code.symbols},
                            {"radii", encoded.code.radii}};
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::ostringstream summary;
    summary << options.skeleton << ": " << code_kind_name(encode_options.kind) << " code of " << counts.internodes << " internodes ("
            << counts.forks << " forks, " << counts.tips << " tips), " << encoded.code.symbols.size() << " symbols; F6 " << f6_length
            << ", DBF6 " << dbf6_length << " (DBF6/F6 " << (f6_length ? static_cast<double>(dbf6_length) / f6_length : 0.0) << ")\n"
            << "  resolution " << encoded.resolution << ", internode length " << encoded.internode_length << " m"
            << (encode_options.internode_length == 0.0 ? " (median edge)" : "") << ", voxel size " << encoded.geometry.voxel_size
            << " m, vertex error bound " << bound << " m\n"
            << "  radius unit " << encoded.geometry.radius_unit << " m, root radius " << encoded.geometry.root_radius;
    if (options.print_code) {
        // stdout carries exactly the code and the radii so it can be piped; the summary goes to the log.
        std::cout << encoded.code.symbols << "\n" << join_radii(encoded.code.radii) << "\n";
        log_info(summary.str());
    } else {
        std::cout << summary.str() << "\n";
    }
    return 0;
}

ChainCode code_from_options(const std::string& symbols, const std::string& radii, CodeKind kind) {
    ChainCode code;
    code.kind = kind;
    code.symbols = symbols;
    code.radii = parse_radius_list(radii, "--radii");
    return code;
}

nlohmann::json lod_json(const ChainCode& code, int level, double threshold) {
    return {{"lod", level},         {"threshold", threshold}, {"internodes", code.radii.size()}, {"code_length", code.symbols.size()},
            {"code", code.symbols}, {"radii", code.radii}};
}

int run_lod(const LodCliOptions& options, const OptionTable& table, const GlobalOptions& global) {
    // LOD reduction does not depend on the code kind: F6 and DBF6 prune identically.
    const ChainCode code = code_from_options(options.code, options.radii, CodeKind::DBF6);
    const bool by_levels = options.levels > 0;
    const std::vector<double> thresholds =
            by_levels ? lod_thresholds(branch_thicknesses(code), options.levels) : std::vector<double>{options.threshold};
    const std::vector<ChainCode> levels = lod_chain(code, thresholds, "--code");
    if (global.json) {
        nlohmann::json j = {{"treelobes", kVersion}, {"options", table.json()}, {"input_length", code.symbols.size()}};
        if (by_levels) {
            j["levels"] = nlohmann::json::array();
            for (std::size_t k = 0; k < levels.size(); ++k)
                j["levels"].push_back(lod_json(levels[k], static_cast<int>(k), k ? thresholds[k - 1] : 0.0));
        } else {
            j.update(lod_json(levels.back(), 1, options.threshold));
        }
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    if (!by_levels) {
        std::cout << levels.back().symbols << "\n" << join_radii(levels.back().radii) << "\n";
        return 0;
    }
    for (std::size_t k = 0; k < levels.size(); ++k) {
        std::cout << "# LOD " << k;
        if (k) std::cout << " (threshold " << thresholds[k - 1] << ")";
        std::cout << ": " << levels[k].radii.size() << " internodes, " << levels[k].symbols.size() << " symbols\n"
                  << levels[k].symbols << "\n"
                  << join_radii(levels[k].radii) << "\n";
    }
    return 0;
}

int run_decode(const DecodeCliOptions& options, const OptionTable& table, const GlobalOptions& global) {
    const ChainCode code = code_from_options(options.code, options.radii, options.f6 ? CodeKind::F6 : CodeKind::DBF6);
    CodeGeometry geometry;
    geometry.voxel_size = options.internode_length / options.resolution;  // Eq. 2
    geometry.radius_unit = options.radius_unit;
    geometry.root_radius = options.root_radius >= 0 ? options.root_radius : (code.radii.empty() ? 0 : code.radii[0]);
    const TreeGraph tree = decode_tree(code, geometry, "--code");
    write_skeleton_ply(tree, options.out, !options.ascii,
                       {code_parameters_comment({options.resolution, options.internode_length, options.radius_unit})});

    const SymbolCounts counts = count_symbols(code.symbols);
    if (global.json) {
        std::cout << nlohmann::json{{"treelobes", kVersion},
                                    {"options", table.json()},
                                    {"kind", code_kind_name(code.kind)},
                                    {"internodes", counts.internodes},
                                    {"nodes", tree.size()},
                                    {"tips", tree.tip_count()},
                                    {"voxel_size", geometry.voxel_size},
                                    {"root_radius", geometry.root_radius},
                                    {"out", options.out}}
                             .dump(2)
                  << "\n";
        return 0;
    }
    std::cout << "decoded " << code_kind_name(code.kind) << " code of " << counts.internodes << " internodes: " << tree.size() << " nodes, "
              << tree.tip_count() << " tips, voxel size " << geometry.voxel_size << " m; wrote " << options.out << "\n";
    return 0;
}

bool is_forest_file(const fs::path& path) {
    std::ifstream file(path, std::ios::binary);
    char magic[4] = {};
    file.read(magic, 4);
    return file.gcount() == 4 && std::string(magic, 4) == "DBFF";
}

// A decoded skeleton records the parameters of its code (tree_code.hpp CodeParameters).
void write_tree_output(const TreeGraph& tree, const fs::path& out, bool ascii, const CodeParameters& code) {
    write_skeleton_ply(tree, out, !ascii, {code_parameters_comment(code)});
}

CodeParameters code_parameters_of(const StoredTree& tree) { return {tree.resolution, tree.internode_length, tree.radius_unit}; }

int run_decode_forest(const DecodeFileCliOptions& options, const OptionTable& table, const GlobalOptions& global) {
    ForestReader forest{fs::path(options.input)};
    std::vector<std::size_t> selected;
    if (options.tree >= 0) {
        forest.entry(static_cast<std::size_t>(options.tree));  // usage error when out of range
        selected.push_back(static_cast<std::size_t>(options.tree));
    } else {
        for (std::size_t i = 0; i < forest.size(); ++i) selected.push_back(i);
    }
    // Everything is decoded before anything is written: a damaged tree leaves no partial output.
    std::vector<TreeGraph> trees;
    std::vector<CodeParameters> parameters;
    nlohmann::json written = nlohmann::json::array();
    std::size_t internodes = 0;
    for (std::size_t i : selected) {
        std::vector<StreamSizes> sizes;
        const StoredTree stored = forest.read(i, options.lod, &sizes);
        trees.push_back(
                place_tree(decode_stored_tree(stored, options.lod, options.input + ": tree " + std::to_string(i)), forest.entry(i)));
        parameters.push_back(code_parameters_of(stored));
        internodes += sizes[static_cast<std::size_t>(options.lod)].internodes;
        nlohmann::json item = {{"tree", i}, {"name", forest.entry(i).name}, {"nodes", trees.back().size()}};
        if (options.stats) item["lods"] = lod_stats_json(stored, sizes);
        written.push_back(item);
    }
    if (options.tree >= 0) {
        write_tree_output(trees[0], options.out, options.ascii, parameters[0]);
        written[0]["out"] = options.out;
    } else {
        // One skeleton PLY per tree in the --out directory, named by index and tree name.
        fs::create_directories(options.out);
        for (std::size_t k = 0; k < selected.size(); ++k) {
            char prefix[16];
            std::snprintf(prefix, sizeof prefix, "%05zu", selected[k]);
            const std::string name = forest.entry(selected[k]).name;
            const fs::path out = fs::path(options.out) / (std::string(prefix) + (name.empty() ? "" : "_" + name) + ".ply");
            write_tree_output(trees[k], out, options.ascii, parameters[k]);
            written[k]["out"] = out.string();
        }
    }
    if (global.json) {
        std::cout << nlohmann::json{{"treelobes", kVersion},  {"options", table.json()},
                                    {"input", options.input}, {"trees_in_file", forest.size()},
                                    {"lod", options.lod},     {"internodes", internodes},
                                    {"decoded", written}}
                             .dump(2)
                  << "\n";
        return 0;
    }
    std::cout << "decoded " << selected.size() << " of " << forest.size() << " trees (LOD " << options.lod << ", " << internodes
              << " internodes) from " << options.input << " into " << options.out << "\n";
    return 0;
}

int run_decode_file(const DecodeFileCliOptions& options, const OptionTable& table, const GlobalOptions& global) {
    if (options.lod < 0) throw Error::usage("--lod must be 0 or more");
    if (is_forest_file(options.input)) return run_decode_forest(options, table, global);
    if (options.tree >= 0) throw Error::usage("--tree applies to .forest files; " + options.input + " holds one tree");
    std::vector<StreamSizes> sizes;
    const StoredTree stored = read_tree_file(options.input, options.lod, &sizes);
    const TreeGraph tree = decode_stored_tree(stored, options.lod, options.input);
    write_tree_output(tree, options.out, options.ascii, code_parameters_of(stored));
    const StreamSizes& level = sizes[static_cast<std::size_t>(options.lod)];
    if (global.json) {
        nlohmann::json j = {{"treelobes", kVersion},
                            {"options", table.json()},
                            {"input", options.input},
                            {"kind", code_kind_name(stored.kind)},
                            {"coder", coder_name(stored.coder)},
                            {"lods_in_file", stored.lods.size()},
                            {"lod", options.lod},
                            {"internodes", level.internodes},
                            {"nodes", tree.size()},
                            {"tips", tree.tip_count()},
                            {"out", options.out}};
        if (options.stats) j["lods"] = lod_stats_json(stored, sizes);
        std::cout << j.dump(2) << "\n";
        return 0;
    }
    std::cout << "decoded LOD " << options.lod << " of " << stored.lods.size() << " (" << level.internodes << " internodes, "
              << coder_name(stored.coder) << " coder): " << tree.size() << " nodes, " << tree.tip_count() << " tips; wrote " << options.out
              << "\n";
    if (options.stats) print_lod_stats(stored, sizes);
    return 0;
}

void add_encode(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<EncodeCliOptions>();
    CLI::App* sub = app.add_subcommand(
            "encode",
            "Encode a skeleton as an F6/DBF6 chain code and radius list (Strnad et al. 2020); with --out, compress it into "
            "a .dbf6 file, or many trees (--forest) into a .forest file");
    auto table = std::make_shared<OptionTable>(sub);
    auto* skeleton = sub->add_option("skeleton", options->skeleton, "Skeleton PLY (vertex 0 is the root) or .tlobe");
    auto* forest = table->add("--forest", options->forest,
                              "Directory of skeleton PLY/.tlobe files, or a list file with lines PATH [X Y Z [AZIMUTH_DEG]]");
    skeleton->excludes(forest);
    forest->excludes(skeleton);
    auto* out = table->add("--out", options->out, "Output .dbf6 file (one tree) or .forest file (--forest)");
    auto* resolution = table->add("--resolution", options->resolution,
                                  "Voxels per internode length (r of Eq. 2); required unless the skeleton is a "
                                  "decoded one, which records r, l and the radius unit of its code")
                               ->check(cli::PositiveNumber);
    auto* internode_length = table->add("--internode-length", options->internode_length,
                                        "Internode length l in metres, or 'auto' for the median edge length (per "
                                        "tree; a decoded skeleton's recorded l when not given)");
    auto* radius_unit = table->add("--radius-unit", options->radius_unit,
                                   "Metres per radius step of the radius list (a decoded skeleton's recorded unit "
                                   "when not given)")
                                ->check(cli::PositiveNumber);
    table->add_flag("--f6", options->f6, "Plain F6 code instead of the differential DBF6");
    auto* print = table->add_flag("--print-code", options->print_code, "Print the code on one line and the radii on the next");
    auto* lods = table->add("--lods", options->lods, "Levels of detail stored in the file (1 = full detail only)")
                         ->check(CLI::Range(1, kMaxLods));
    auto* coder = table->add("--coder", options->coder, "Compression: ic (Strnad et al. 2020, §3.3) or best")
                          ->check(CLI::IsMember({"ic", "best"}));
    table->add_flag("--stats", options->stats, "Report the size of every stream (per LOD, per tree)");
    print->excludes(out);
    sub->callback([options, table, skeleton, forest, out, lods, coder, resolution, internode_length, radius_unit, &global, &job] {
        if (skeleton->count() == 0 && forest->count() == 0) throw CLI::RequiredError("skeleton or --forest");
        if (forest->count() && resolution->count() == 0) throw CLI::RequiredError("--resolution (with --forest)");
        options->resolution_given = resolution->count() > 0;
        options->internode_length_given = internode_length->count() > 0;
        options->radius_unit_given = radius_unit->count() > 0;
        if (forest->count() && out->count() == 0) throw CLI::RequiredError("--out (with --forest)");
        if (out->count() == 0 && (lods->count() || coder->count()))
            throw CLI::ValidationError("--lods/--coder", "apply to files: give --out");
        job = [options, table, &global] { return run_encode(*options, *table, global); };
    });
}

void add_decode(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<DecodeFileCliOptions>();
    CLI::App* sub = app.add_subcommand("decode", "Decode a .dbf6 tree or .forest trees into skeleton PLY files");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("input", options->input, "A .dbf6 or .forest file")->required();
    table->add("--lod", options->lod, "Level of detail to decode (0 = full detail)")->check(cli::NonNegativeNumber);
    table->add("--tree", options->tree, "Forest files: decode only tree I (0-based) into the --out PLY")->check(cli::NonNegativeNumber);
    table->add("--out", options->out, "Output skeleton PLY; for a whole forest (no --tree) a directory receiving one PLY per tree")
            ->required();
    table->add_flag("--ascii", options->ascii, "Write ASCII PLY instead of binary");
    table->add_flag("--stats", options->stats, "Report the size of every stream");
    sub->callback(
            [options, table, &global, &job] { job = [options, table, &global] { return run_decode_file(*options, *table, global); }; });
}

void add_lod(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<LodCliOptions>();
    CLI::App* sub = app.add_subcommand("lod", "Prune lateral branches thinner than a threshold directly on a chain code");
    auto table = std::make_shared<OptionTable>(sub);
    table->add("--code", options->code, "Chain code (F6 or DBF6)")->required();
    table->add("--radii", options->radii, "Comma-separated radii, one per internode")->required();
    auto* threshold = table->add("--threshold", options->threshold, "Prune laterals whose first radius is below T (radius units)");
    auto* levels =
            table->add("--levels", options->levels,
                       "Print K LODs with thresholds at uniform positions of the sorted unique branch thicknesses (laterals' first radii)")
                    ->check(cli::PositiveNumber);
    threshold->excludes(levels);
    levels->excludes(threshold);
    sub->callback([options, table, threshold, levels, &global, &job] {
        if (threshold->count() == 0 && levels->count() == 0) throw CLI::RequiredError("--threshold or --levels");
        job = [options, table, &global] { return run_lod(*options, *table, global); };
    });
}

void add_decode_code(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<DecodeCliOptions>();
    CLI::App* sub = app.add_subcommand("decode-code", "Decode a chain code and radius list into a skeleton PLY");
    auto table = std::make_shared<OptionTable>(sub);
    table->add("--code", options->code, "Chain code")->required();
    table->add("--radii", options->radii, "Comma-separated radii, one per internode")->required();
    table->add("--resolution", options->resolution, "Resolution r used for encoding")->required()->check(cli::PositiveNumber);
    table->add("--internode-length", options->internode_length, "Internode length l (metres) used for encoding")
            ->required()
            ->check(cli::PositiveNumber);
    table->add("--radius-unit", options->radius_unit, "Metres per radius step")->check(cli::PositiveNumber);
    table->add("--root-radius", options->root_radius, "Root vertex radius in radius units (default: the first radius)")
            ->check(cli::NonNegativeNumber);
    table->add_flag("--f6", options->f6, "The code is plain F6 (default: DBF6)");
    table->add_flag("--ascii", options->ascii, "Write an ASCII PLY instead of binary");
    table->add("--out", options->out, "Output skeleton PLY")->required();
    sub->callback([options, table, &global, &job] { job = [options, table, &global] { return run_decode(*options, *table, global); }; });
}

}  // namespace

void add_encode_commands(CLI::App& app, const GlobalOptions& global, Job& job) {
    add_encode(app, global, job);
    add_decode(app, global, job);
    add_lod(app, global, job);
    add_decode_code(app, global, job);
}

}  // namespace treelobes::cli
