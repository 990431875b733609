// `treelobes multires INPUT|--string S --out DIR`: the hybrid multiresolution representation of
// Lluch et al. 2010 for the branches. The input (an L-system file, a bracketed module string or a skeleton
// PLY, which is first converted into a bracketed string) becomes a tADT and a multiresolution
// chain with SAVE/RESTORE entries; LOD k is the chain up to its (k+1)-th RESTORE. Writes the chain
// (chain.txt), one skeleton PLY per requested LOD (optionally a tube mesh), the leaves of each LOD
// when the L-system places any, and summary.json. When there are leaves, the foliage bounding-box
// hierarchy (Lluch et al. 2010, via Ong's seminar report, §3.2) is built too: foliage.json, and the six diagonal-plane textures of every
// box above the volume threshold packed into atlas.png; each LOD then also says which boxes'
// textures stand in for the branches its chain prefix has not reached (combined LOD, §3.3).
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/summary_values.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "core/version.hpp"
#include "geometry/branch_mesh.hpp"
#include "lsystem/foliage.hpp"
#include "lsystem/lsystem.hpp"
#include "lsystem/multires_chain.hpp"
#include "lsystem/tree_string.hpp"
#include "render/foliage_textures.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

namespace treelobes::cli {

namespace {

namespace fs = std::filesystem;
using namespace treelobes::lsystem;

struct MultiresCliOptions {
    std::string input;
    std::string string;
    std::string out;
    std::string metric = "branching-length";
    std::string order = "greedy";
    std::vector<long long> lods;
    bool all = false;
    int steps = -1;       // -1: the file's derivation length
    long long seed = -1;  // -1: the file's seed
    std::vector<std::string> defines;
    std::size_t max_modules = kDefaultMaxModules;
    std::vector<std::string> length_modules{"F", "f"};
    bool mesh = false;
    double texture_threshold = 0.01;
    int texture_size = 128;
    bool texture_planes = false;
    std::string small_foliage = "geometry";
};

// What the chain is built from, with the turtle settings that draw it.
struct Source {
    std::string kind;  // "lsystem", "string", "skeleton"
    ModuleString string;
    TurtleOptions turtle;
    Eigen::Vector3d origin{0, 0, 0};
    std::size_t derived_modules = 0;  // L-system: modules before the homomorphism
};

std::map<std::string, double> parse_defines(const std::vector<std::string>& items) {
    std::map<std::string, double> defines;
    for (const auto& item : items) {
        const auto eq = item.find('=');
        if (eq == std::string::npos || eq == 0) throw Error::usage("--define " + item + ": expected NAME=VALUE");
        try {
            std::size_t used = 0;
            const double value = std::stod(item.substr(eq + 1), &used);
            if (used != item.size() - eq - 1 || !std::isfinite(value)) throw std::invalid_argument("trailing text");
            defines[item.substr(0, eq)] = value;
        } catch (const std::exception&) {
            throw Error::usage("--define " + item + ": the value is not a number");
        }
    }
    return defines;
}

bool is_ply(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext == ".ply";
}

Source load_source(const MultiresCliOptions& o) {
    Source source;
    if (!o.string.empty()) {
        source.kind = "string";
        source.string = parse_module_string(o.string, "--string");
        return source;
    }
    if (is_ply(o.input)) {
        source.kind = "skeleton";
        const TreeGraph tree = read_skeleton_ply(o.input);
        tree.validate(o.input);
        TreeString converted = tree_to_module_string(tree);
        source.string = std::move(converted.modules);
        source.turtle = converted.turtle;
        source.origin = tree.origin;
        return source;
    }
    source.kind = "lsystem";
    ParseOptions parse;
    parse.defines = parse_defines(o.defines);
    const LSystem system = load_lsystem(o.input, parse);
    DeriveOptions derive_options;
    if (o.steps >= 0) derive_options.steps = o.steps;
    if (o.seed >= 0) derive_options.seed = static_cast<std::uint64_t>(o.seed);
    derive_options.max_modules = o.max_modules;
    const ModuleString derived = derive(system, derive_options);
    source.derived_modules = derived.size();
    source.string = apply_homomorphism(system, derived, derive_options);
    source.turtle = system.turtle;
    check_brackets(source.string, o.input);
    return source;
}

// LOD levels to write: --all, the given --lod values, or the coarsest and the full tree.
std::vector<std::size_t> requested_lods(const MultiresCliOptions& o, std::size_t count) {
    std::vector<std::size_t> lods;
    if (o.all) {
        for (std::size_t k = 0; k < count; ++k) lods.push_back(k);
        return lods;
    }
    if (o.lods.empty()) {
        lods.push_back(0);
        if (count > 1) lods.push_back(count - 1);
        return lods;
    }
    for (long long k : o.lods) {
        if (k < 0 || static_cast<std::size_t>(k) >= count)
            throw Error::usage("--lod " + std::to_string(k) + ": the chain has " + std::to_string(count) + " levels (0.." +
                               std::to_string(count - 1) + ")");
        lods.push_back(static_cast<std::size_t>(k));
    }
    std::sort(lods.begin(), lods.end());
    lods.erase(std::unique(lods.begin(), lods.end()), lods.end());
    return lods;
}

std::string lod_name(std::size_t k, std::size_t count) {
    const int digits = static_cast<int>(std::to_string(count - 1).size());
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "lod_%0*zu", digits, k);
    return buffer;
}

void write_leaves_csv(const std::vector<LeafPlacement>& leaves, const fs::path& path) {
    write_atomically(path, [&](std::ostream& out) {
        out.precision(9);  // float round trip
        out << "x,y,z,hx,hy,hz,ux,uy,uz,size,node\n";
        for (const auto& l : leaves)
            out << l.position.x() << ',' << l.position.y() << ',' << l.position.z() << ',' << l.heading.x() << ',' << l.heading.y() << ','
                << l.heading.z() << ',' << l.up.x() << ',' << l.up.y() << ',' << l.up.z() << ',' << l.size << ',' << l.node << '\n';
    });
}

// Three leaf tones, picked per leaf by a fixed hash so textures are deterministic and not flat.
constexpr render::Rgba kLeafTones[3] = {{58, 128, 40, 255}, {86, 150, 52, 255}, {42, 104, 36, 255}};

std::array<render::Image, 6> box_textures(const FoliageBox& box, const std::vector<LeafPlacement>& leaves, const Eigen::Vector3d& origin,
                                          int size) {
    std::vector<LeafPlacement> tone_leaves[3];
    for (std::size_t l = box.leaf_begin; l < box.leaf_end; ++l) tone_leaves[(l * 2654435761u >> 7) % 3].push_back(leaves[l]);
    TriangleMesh meshes[3];
    std::vector<render::FoliageLayer> layers;
    for (int t = 0; t < 3; ++t) {
        meshes[t] = foliage_mesh(tone_leaves[t]);
        meshes[t].origin = origin;
        layers.push_back({&meshes[t], kLeafTones[t]});
    }
    // 4 x 4 supersampling, fewer samples for large textures (the raster stays <= 2048 pixels wide).
    const int supersample = std::clamp(2048 / size, 1, 4);
    return render::render_diagonal_textures(layers, origin + box.box.min(), origin + box.box.max(), size, supersample);
}

nlohmann::json vector_json(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// Foliage hierarchy, textures and atlas; returns the "foliage" block of summary.json.
nlohmann::json write_foliage(const FoliageHierarchy& hierarchy, const std::vector<LeafPlacement>& leaves, const Eigen::Vector3d& origin,
                             const MultiresCliOptions& o, const fs::path& out) {
    std::vector<render::Image> tiles;
    nlohmann::json boxes = nlohmann::json::array();
    if (o.texture_planes) fs::create_directories(out / "textures");
    for (std::size_t b = 0; b < hierarchy.boxes.size(); ++b) {
        const FoliageBox& box = hierarchy.boxes[b];
        nlohmann::json entry = {{"id", b},
                                {"parent", box.parent},
                                {"children", box.children},
                                {"depth", box.depth},
                                {"tadt_node", box.tadt_node},
                                {"leaves", box.leaf_count()},
                                {"own_leaves", box.own_leaves},
                                {"min", vector_json(origin + box.box.min())},
                                {"max", vector_json(origin + box.box.max())},
                                {"volume_ratio", box.volume_ratio},
                                {"textured", box.textured}};
        if (box.textured) {
            const auto textures = box_textures(box, leaves, origin, o.texture_size);
            const auto planes = render::diagonal_planes(origin + box.box.min(), origin + box.box.max());
            nlohmann::json planes_json = nlohmann::json::array();
            for (std::size_t k = 0; k < planes.size(); ++k) {
                nlohmann::json plane = {{"plane", planes[k].name},
                                        {"tile", tiles.size()},
                                        {"corner", vector_json(planes[k].corner)},
                                        {"u", vector_json(planes[k].u)},
                                        {"v", vector_json(planes[k].v)}};
                if (o.texture_planes) {
                    const std::string file = "textures/box_" + std::to_string(b) + "_" + planes[k].name + ".png";
                    render::write_png(textures[k], out / file);
                    plane["png"] = file;
                }
                planes_json.push_back(plane);
                tiles.push_back(textures[k]);
            }
            entry["planes"] = planes_json;
        }
        boxes.push_back(entry);
    }
    const std::size_t textured = tiles.size() / 6;
    // Foliage-only levels: the cut of the textured hierarchy at each depth, until it stops refining.
    nlohmann::json levels = nlohmann::json::array();
    std::size_t previous = 0;
    for (int depth = 0; depth <= hierarchy.max_depth(); ++depth) {
        const std::size_t boxes_in_cut = foliage_cut(hierarchy, depth).size();
        if (depth > 0 && boxes_in_cut == previous) break;
        levels.push_back({{"depth", depth}, {"boxes", boxes_in_cut}, {"texture_quads", 6 * boxes_in_cut}});
        previous = boxes_in_cut;
    }
    // Whole boxes per atlas row (six tiles each), about as many rows as columns.
    const int columns = 6 * std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(textured) / 6.0))));
    nlohmann::json summary = {{"leaves", hierarchy.leaf_count},
                              {"boxes", hierarchy.boxes.size()},
                              {"hierarchy_depth", hierarchy.max_depth() + 1},
                              {"texture_threshold", o.texture_threshold},
                              {"textured_boxes", textured},
                              {"textures", tiles.size()},
                              {"texture_size", o.texture_size},
                              {"texture_bytes_rgba", tiles.size() * static_cast<std::size_t>(o.texture_size) * o.texture_size * 4},
                              {"levels", levels},
                              {"hierarchy", "foliage.json"}};
    if (!tiles.empty()) {
        render::write_png(render::pack_atlas(tiles, columns), out / "atlas.png");
        summary["atlas"] = "atlas.png";
        summary["atlas_columns"] = columns;
        summary["atlas_png_bytes"] = fs::file_size(out / "atlas.png");
    }
    nlohmann::json doc = {{"texture_size", o.texture_size},
                          {"atlas", tiles.empty() ? nlohmann::json() : nlohmann::json("atlas.png")},
                          {"atlas_columns", columns},
                          {"note",
                           "tile i sits at pixel ((i % atlas_columns) * texture_size, (i / atlas_columns) * "
                           "texture_size); texel (x, y) of a tile lies at corner + s*u + t*v, s = (x + 0.5) / "
                           "texture_size, t = 1 - (y + 0.5) / texture_size"},
                          {"boxes", boxes}};
    write_file_atomically(out / "foliage.json", doc.dump(1) + "\n");
    return summary;
}

// Foliage: hierarchy and textures from the leaves of the whole string (string order).
struct Foliage {
    std::optional<FoliageHierarchy> hierarchy;
    std::vector<LeafPlacement> leaves;  // string order, as the hierarchy indexes them
    nlohmann::json summary;
};

Foliage build_foliage(const Source& source, const MultiresChain& chain, const MultiresCliOptions& o, const fs::path& out) {
    Foliage foliage;
    foliage.leaves = interpret(source.string, source.turtle).leaves;
    FoliageOptions foliage_options;
    foliage_options.texture_threshold = o.texture_threshold;
    foliage.hierarchy = build_foliage_hierarchy(chain.tadt, foliage.leaves, foliage_options);
    foliage.summary = write_foliage(*foliage.hierarchy, foliage.leaves, source.origin, o, out);
    return foliage;
}

// One level of detail: its skeleton (and leaves, mesh) written to `out`, its summary entry
// returned; the extraction time is added to extract_seconds.
nlohmann::json write_lod(const MultiresChain& chain, std::size_t k, const Source& source, const Foliage& foliage, float full_length,
                         const MultiresCliOptions& o, const fs::path& out, double& extract_seconds) {
    const auto t = std::chrono::steady_clock::now();
    TurtleResult lod = extract_lod(chain, k, source.turtle);
    extract_seconds += seconds_since(t);
    std::optional<FoliageLod> lod_foliage;
    if (foliage.hierarchy) {
        // Leaves of the prefix's ornaments belong with their branches (foliage.hpp).
        lod_foliage = foliage_for_prefix(chain.tadt, *foliage.hierarchy, visited_nodes(chain, chain.lod_end(k)));
        for (std::size_t l : lod_foliage->attached_leaves) lod.leaves.push_back(foliage.leaves[l]);
        if (o.small_foliage == "geometry")
            for (int b : lod_foliage->small_boxes) {
                const FoliageBox& box = foliage.hierarchy->boxes[static_cast<std::size_t>(b)];
                lod.leaves.insert(lod.leaves.end(), foliage.leaves.begin() + static_cast<std::ptrdiff_t>(box.leaf_begin),
                                  foliage.leaves.begin() + static_cast<std::ptrdiff_t>(box.leaf_end));
            }
    }
    lod.tree.origin = source.origin;
    const std::string base = lod_name(k, chain.lod_count());
    write_skeleton_ply(lod.tree, out / (base + ".ply"));
    nlohmann::json entry = {{"lod", k},
                            {"entries", chain.lod_end(k)},
                            {"nodes", lod.tree.size()},
                            {"tips", lod.tree.tip_count()},
                            {"length", lod.tree.total_length()},
                            {"length_fraction", full_length > 0 ? lod.tree.total_length() / full_length : 1.0},
                            {"leaves", lod.leaves.size()},
                            {"skeleton", base + ".ply"}};
    if (!lod.leaves.empty()) {
        write_leaves_csv(lod.leaves, out / (base + ".leaves.csv"));
        entry["leaves_csv"] = base + ".leaves.csv";
    }
    if (lod_foliage) {
        const FoliageLod& f = *lod_foliage;
        entry["foliage"] = {{"leaves_as_geometry", lod.leaves.size()},
                            {"textured_boxes", f.textured_boxes},
                            {"texture_quads", 6 * f.textured_boxes.size()},
                            {"leaves_in_textures", f.leaves_in_textures},
                            {"small_branches", f.small_boxes.size()},
                            {"leaves_omitted", o.small_foliage == "omit" ? f.leaves_in_small_boxes : 0}};
    }
    if (o.mesh && lod.tree.size() > 1) {
        write_mesh(build_branch_mesh(lod.tree), out / (base + ".mesh.ply"));
        entry["mesh"] = base + ".mesh.ply";
    }
    return entry;
}

// The human-readable report of a run (without --json).
void print_multires_report(const nlohmann::json& summary, const MultiresCliOptions& o, const fs::path& out) {
    std::cout << "multires: " << summary["input"].get<std::string>() << " -> " << o.out << "\n"
              << "  " << summary["modules"].get<std::size_t>() << " modules, tADT " << summary["tadt_nodes"].get<std::size_t>()
              << " nodes, chain " << summary["chain_entries"].get<std::size_t>() << " entries (" << summary["saves"].get<std::size_t>()
              << " SAVE, " << summary["restores"].get<std::size_t>() << " RESTORE), " << summary["lod_count"].get<std::size_t>()
              << " LODs (" << summary["lods_adding_length"].get<std::size_t>() << " add branch length); metric "
              << summary["metric"].get<std::string>() << ", order " << summary["order"].get<std::string>() << "\n";
    for (const auto& entry : summary["lods"]) {
        char line[200];
        std::snprintf(line, sizeof line, "  LOD %zu: %zu nodes, %zu tips, length %.4g (%.1f %%) -> %s\n", entry["lod"].get<std::size_t>(),
                      entry["nodes"].get<std::size_t>(), entry["tips"].get<std::size_t>(), entry["length"].get<double>(),
                      100.0 * entry["length_fraction"].get<double>(), entry["skeleton"].get<std::string>().c_str());
        std::cout << line;
    }
    if (summary.contains("foliage")) {
        const nlohmann::json& foliage = summary["foliage"];
        std::cout << "  foliage: " << foliage["leaves"] << " leaves, " << foliage["boxes"] << " boxes (depth " << foliage["hierarchy_depth"]
                  << "), " << foliage["textures"] << " textures of " << o.texture_size << "x" << o.texture_size << " ("
                  << foliage["texture_bytes_rgba"] << " bytes RGBA) for boxes above volume ratio " << o.texture_threshold << "\n";
    }
    std::cout << "  chain: " << (out / "chain.txt").string() << ", summary: " << (out / "summary.json").string() << "\n";
}

int run_multires(const MultiresCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    if (o.input.empty() == o.string.empty()) throw Error::usage("multires: give either an INPUT file or --string");
    const auto metric = parse_chain_metric(o.metric);
    const auto order = parse_chain_order(o.order);
    const auto t0 = std::chrono::steady_clock::now();
    Source source = load_source(o);
    const double load_seconds = seconds_since(t0);

    const auto t1 = std::chrono::steady_clock::now();
    MultiresOptions chain_options;
    chain_options.metric = *metric;
    chain_options.order = *order;
    chain_options.tadt.length_modules = o.length_modules;
    const std::string name = o.string.empty() ? o.input : "--string";
    const MultiresChain chain = build_multires_chain(source.string, chain_options, name);
    const double chain_seconds = seconds_since(t1);

    const fs::path out(o.out);
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec) throw Error::input(o.out, "cannot create the output folder: " + ec.message());
    write_file_atomically(out / "chain.txt", chain_file_text(chain));

    const std::vector<std::size_t> lods = requested_lods(o, chain.lod_count());
    const TurtleResult full = extract_lod(chain, chain.lod_count() - 1, source.turtle);
    const float full_length = full.tree.total_length();

    const auto t2 = std::chrono::steady_clock::now();
    const Foliage foliage = full.leaves.empty() ? Foliage{} : build_foliage(source, chain, o, out);
    const double foliage_seconds = seconds_since(t2);
    nlohmann::json lod_json = nlohmann::json::array();
    double extract_seconds = 0.0;
    for (std::size_t k : lods) lod_json.push_back(write_lod(chain, k, source, foliage, full_length, o, out, extract_seconds));

    std::size_t saves = 0;
    for (const auto& e : chain.entries) saves += e.kind == ChainEntry::Kind::save;
    // Levels that add branch length (the others only add apices or leaves).
    std::size_t growing = 1;
    for (std::size_t k = 1; k < chain.lod_count(); ++k) growing += chain.lod_length[k] > chain.lod_length[k - 1];
    nlohmann::json summary = {
            {"treelobes", kVersion},
            {"command", "multires"},
            {"options", table.json()},
            {"input", name},
            {"input_kind", source.kind},
            {"metric", to_string(*metric)},
            {"order", to_string(*order)},
            {"modules", source.string.size()},
            {"internodes", source.string.count("F")},
            {"tadt_nodes", chain.tadt.nodes.size()},
            {"chain_entries", chain.entries.size()},
            {"saves", saves},
            {"restores", chain.restores.size()},
            {"lod_count", chain.lod_count()},
            {"lods_adding_length", growing},
            {"total_length", full_length},
            {"chain", "chain.txt"},
            {"lods", lod_json},
            {"seconds", {{"load", load_seconds}, {"chain", chain_seconds}, {"foliage", foliage_seconds}, {"extract", extract_seconds}}}};
    if (foliage.hierarchy) summary["foliage"] = foliage.summary;
    if (source.kind == "lsystem") summary["derived_modules"] = source.derived_modules;
    write_file_atomically(out / "summary.json", summary.dump(2) + "\n");

    if (global.json) {
        std::cout << summary.dump(2) << "\n";
        return 0;
    }
    print_multires_report(summary, o, out);
    return 0;
}

}  // namespace

void add_multires_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto o = std::make_shared<MultiresCliOptions>();
    CLI::App* sub = app.add_subcommand(
            "multires", "Multiresolution chain (Lluch et al. 2010) of an L-system, a bracketed string or a skeleton PLY; writes LODs");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("input", o->input, "L-system file (docs/lsystem.md) or skeleton PLY");
    table->add("--string", o->string, "A bracketed module string instead of a file, e.g. 'C1[C2[C3][C4]][C5]'");
    table->add("--out", o->out, "Output folder")->required();
    table->add("--metric", o->metric, "Child order: branching-length (default), children, descendants, longest-path")
            ->check(CLI::IsMember({"branching-length", "children", "descendants", "longest-path", "branching_length", "longest_path"}));
    table->add("--order", o->order, "Resume at: greedy (largest remaining branch, default) or depth-first")
            ->check(CLI::IsMember({"greedy", "depth-first", "depth_first"}));
    auto* lod = table->add("--lod", o->lods, "LOD level(s) to write (0 = coarsest); default: coarsest and full");
    table->add_flag("--all", o->all, "Write every LOD level")->excludes(lod);
    table->add("--steps", o->steps, "Derivation length (overrides the file)")->check(CLI::Range(0, kMaxDerivationLength));
    table->add("--seed", o->seed, "Seed of stochastic rules (overrides the file)")->check(cli::NonNegativeNumber);
    table->add("--define,-D", o->defines, "Override a #define constant: NAME=VALUE (repeatable)");
    table->add("--max-modules", o->max_modules, "Largest module string a derivation may produce")
            ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000'000}));
    table->add("--length-modules", o->length_modules, "Modules whose first parameter is a length in the tADT")->delimiter(',');
    table->add_flag("--mesh", o->mesh, "Also write a tube mesh per LOD (<lod>.mesh.ply)");
    table->add("--texture-threshold", o->texture_threshold,
               "Foliage boxes whose volume / root volume exceeds this get six textures (0 <= R < 1)")
            ->check(CLI::Range(0.0, 0.999999));
    table->add("--texture-size", o->texture_size, "Texture width and height in pixels")->check(CLI::Range(8, 1024));
    table->add_flag("--texture-planes", o->texture_planes, "Also write every texture as its own PNG (textures/)");
    table->add("--small-foliage", o->small_foliage,
               "Leaves of unreached sub-branches below the texture threshold: geometry (default) or omit")
            ->check(CLI::IsMember({"geometry", "omit"}));
    sub->callback([o, table, &global, &job] { job = [o, table, &global] { return run_multires(*o, *table, global); }; });
}

}  // namespace treelobes::cli
