// `treelobes encode`, `treelobes lod` and `treelobes decode-code`: F6/DBF6 chain codes of
// skeletons (seed 000 §3.1-3.2) on the command line. Codes and radius lists travel as text
// (the code on one line, the comma-separated radii on the next); files come with compression.
#include "apps/command.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/skeleton_io.hpp"
#include "core/version.hpp"
#include "encode/chain_code.hpp"
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"

#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

namespace treelobes::cli {

namespace {

using namespace treelobes::encode;

struct EncodeCliOptions {
    std::string skeleton;
    double resolution = 5.0;
    std::string internode_length = "auto";
    double radius_unit = 0.001;
    bool f6 = false;
    bool print_code = false;
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

// "10,9,5" -> {10, 9, 5}; blanks around values are allowed, an empty text is an empty list.
std::vector<int> parse_radii(const std::string& text) {
    std::vector<int> radii;
    std::stringstream stream(text);
    std::string item;
    while (std::getline(stream, item, ',')) {
        const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
        const std::string value = first == std::string::npos ? "" : item.substr(first, last - first + 1);
        int radius = 0;
        const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), radius);
        if (value.empty() || error != std::errc() || end != value.data() + value.size() || radius < 0)
            throw Error::input("--radii", "value " + std::to_string(radii.size() + 1) + " ('" + value +
                                              "') is not a non-negative integer");
        radii.push_back(radius);
    }
    if (!text.empty() && text.back() == ',') throw Error::input("--radii", "trailing comma after the last radius");
    return radii;
}

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

int run_encode(const EncodeCliOptions& options, const GlobalOptions& global) {
    const TreeGraph tree = read_skeleton_ply(options.skeleton);
    EncodeOptions encode_options;
    encode_options.resolution = options.resolution;
    encode_options.internode_length = parse_internode_length(options.internode_length);
    encode_options.radius_unit = options.radius_unit;
    encode_options.kind = options.f6 ? CodeKind::F6 : CodeKind::DBF6;
    const EncodedTree encoded = encode_tree(tree, encode_options, options.skeleton);

    const SymbolCounts counts = count_symbols(encoded.code.symbols);
    const std::size_t f6_length = write_symbols(encoded.internodes, CodeKind::F6).size();
    const std::size_t dbf6_length = write_symbols(encoded.internodes, CodeKind::DBF6).size();
    const double bound = std::sqrt(3.0) * encoded.geometry.voxel_size / 2.0;
    if (global.json) {
        nlohmann::json j = {{"treelobes", kVersion},
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
    summary << options.skeleton << ": " << code_kind_name(encode_options.kind) << " code of " << counts.internodes
            << " internodes (" << counts.forks << " forks, " << counts.tips << " tips), " << encoded.code.symbols.size()
            << " symbols; F6 " << f6_length << ", DBF6 " << dbf6_length << " (DBF6/F6 "
            << (f6_length ? static_cast<double>(dbf6_length) / f6_length : 0.0) << ")\n"
            << "  resolution " << encoded.resolution << ", internode length " << encoded.internode_length << " m"
            << (encode_options.internode_length == 0.0 ? " (median edge)" : "") << ", voxel size "
            << encoded.geometry.voxel_size << " m, vertex error bound " << bound << " m\n"
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
    code.radii = parse_radii(radii);
    return code;
}

nlohmann::json lod_json(const ChainCode& code, int level, double threshold) {
    return {{"lod", level},
            {"threshold", threshold},
            {"internodes", code.radii.size()},
            {"code_length", code.symbols.size()},
            {"code", code.symbols},
            {"radii", code.radii}};
}

int run_lod(const LodCliOptions& options, const GlobalOptions& global) {
    // LOD reduction does not depend on the code kind: F6 and DBF6 prune identically.
    const ChainCode code = code_from_options(options.code, options.radii, CodeKind::DBF6);
    const bool by_levels = options.levels > 0;
    const std::vector<double> thresholds = by_levels ? lod_thresholds(code.radii, options.levels)
                                                     : std::vector<double>{options.threshold};
    const std::vector<ChainCode> levels = lod_chain(code, thresholds, "--code");
    if (global.json) {
        nlohmann::json j = {{"treelobes", kVersion}, {"input_length", code.symbols.size()}};
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
                  << levels[k].symbols << "\n" << join_radii(levels[k].radii) << "\n";
    }
    return 0;
}

int run_decode(const DecodeCliOptions& options, const GlobalOptions& global) {
    const ChainCode code = code_from_options(options.code, options.radii, options.f6 ? CodeKind::F6 : CodeKind::DBF6);
    CodeGeometry geometry;
    geometry.voxel_size = options.internode_length / options.resolution;  // Eq. 2
    geometry.radius_unit = options.radius_unit;
    geometry.root_radius = options.root_radius >= 0 ? options.root_radius : (code.radii.empty() ? 0 : code.radii[0]);
    const TreeGraph tree = decode_tree(code, geometry, "--code");
    write_skeleton_ply(tree, options.out, !options.ascii);

    const SymbolCounts counts = count_symbols(code.symbols);
    if (global.json) {
        std::cout << nlohmann::json{{"treelobes", kVersion},     {"kind", code_kind_name(code.kind)},
                                    {"internodes", counts.internodes}, {"nodes", tree.size()},
                                    {"tips", tree.tip_count()},     {"voxel_size", geometry.voxel_size},
                                    {"root_radius", geometry.root_radius}, {"out", options.out}}
                         .dump(2)
                  << "\n";
        return 0;
    }
    std::cout << "decoded " << code_kind_name(code.kind) << " code of " << counts.internodes << " internodes: "
              << tree.size() << " nodes, " << tree.tip_count() << " tips, voxel size " << geometry.voxel_size
              << " m; wrote " << options.out << "\n";
    return 0;
}

void add_encode(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<EncodeCliOptions>();
    CLI::App* sub = app.add_subcommand("encode", "Encode a skeleton PLY as an F6/DBF6 chain code and radius list (seed 000)");
    sub->add_option("skeleton", options->skeleton, "Skeleton PLY (vertex 0 is the root)")->required();
    sub->add_option("--resolution", options->resolution, "Voxels per internode length (r of Eq. 2)")
        ->required()
        ->check(CLI::PositiveNumber);
    sub->add_option("--internode-length", options->internode_length,
                    "Internode length l in metres, or 'auto' for the median edge length")
        ->capture_default_str();
    sub->add_option("--radius-unit", options->radius_unit, "Metres per radius step of the radius list")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    sub->add_flag("--f6", options->f6, "Plain F6 code instead of the differential DBF6");
    sub->add_flag("--print-code", options->print_code, "Print the code on one line and the radii on the next");
    sub->callback([options, &global, &job] { job = [options, &global] { return run_encode(*options, global); }; });
}

void add_lod(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<LodCliOptions>();
    CLI::App* sub = app.add_subcommand("lod", "Prune lateral branches thinner than a threshold directly on a chain code");
    sub->add_option("--code", options->code, "Chain code (F6 or DBF6)")->required();
    sub->add_option("--radii", options->radii, "Comma-separated radii, one per internode")->required();
    auto* threshold = sub->add_option("--threshold", options->threshold,
                                      "Prune laterals whose first radius is below T (radius units)");
    auto* levels = sub->add_option("--levels", options->levels,
                                   "Print K LODs with thresholds at uniform positions of the sorted unique radii")
                       ->check(CLI::PositiveNumber);
    threshold->excludes(levels);
    levels->excludes(threshold);
    sub->callback([options, threshold, levels, &global, &job] {
        if (threshold->count() == 0 && levels->count() == 0) throw CLI::RequiredError("--threshold or --levels");
        job = [options, &global] { return run_lod(*options, global); };
    });
}

void add_decode_code(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<DecodeCliOptions>();
    CLI::App* sub = app.add_subcommand("decode-code", "Decode a chain code and radius list into a skeleton PLY");
    sub->add_option("--code", options->code, "Chain code")->required();
    sub->add_option("--radii", options->radii, "Comma-separated radii, one per internode")->required();
    sub->add_option("--resolution", options->resolution, "Resolution r used for encoding")
        ->required()
        ->check(CLI::PositiveNumber);
    sub->add_option("--internode-length", options->internode_length, "Internode length l (metres) used for encoding")
        ->required()
        ->check(CLI::PositiveNumber);
    sub->add_option("--radius-unit", options->radius_unit, "Metres per radius step")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    sub->add_option("--root-radius", options->root_radius, "Root vertex radius in radius units (default: the first radius)")
        ->check(CLI::NonNegativeNumber);
    sub->add_flag("--f6", options->f6, "The code is plain F6 (default: DBF6)");
    sub->add_flag("--ascii", options->ascii, "Write an ASCII PLY instead of binary");
    sub->add_option("--out", options->out, "Output skeleton PLY")->required();
    sub->callback([options, &global, &job] { job = [options, &global] { return run_decode(*options, global); }; });
}

}  // namespace

void add_encode_commands(CLI::App& app, const GlobalOptions& global, Job& job) {
    add_encode(app, global, job);
    add_lod(app, global, job);
    add_decode_code(app, global, job);
}

}  // namespace treelobes::cli
