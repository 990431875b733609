// `treelobes export INPUT --format ply|obj|glb|cityjson|qsm-txt|qsm-csv --out OUT`: our trees
// (skeleton PLY, .tlobe, .dbf6, .forest, or a folder of them) in the formats other tools open
// (docs/export.md). Float formats are written in a local frame with a georef sidecar.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/log.hpp"
#include "core/mesh_io.hpp"
#include "core/version.hpp"
#include "export/cityjson.hpp"
#include "export/gltf.hpp"
#include "export/qsm.hpp"
#include "export/tree_geometry.hpp"
#include "export/tree_input.hpp"
#include "export/tree_measures.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

namespace treelobes::cli {

namespace {

using namespace treelobes::exporting;
namespace fs = std::filesystem;

struct ExportCliOptions {
    std::string input;
    std::string format;
    std::string out;
    int lod = 0;  // LOD of .dbf6 / .forest inputs
    TreeGeometryOptions geometry;
    bool no_leaves = false;
    std::string crs;  // overrides the inputs' sidecar CRS
    CityJsonOptions cityjson;
};

struct TreeSummary {
    std::string name;
    TreeMeasures measures;
    std::optional<double> confidence;
};

// QSM tables: one tree -> OUT is the cylinder file; several -> OUT is a folder of <name>.<ext>.
std::vector<std::string> write_qsm(const ExportInput& input, const ExportCliOptions& o) {
    const bool csv = o.format == "qsm-csv";
    const bool folder = input.trees.size() > 1;
    if (folder) fs::create_directories(o.out);
    std::vector<std::string> written;
    for (const auto& tree : input.trees) {
        const fs::path path = folder ? fs::path(o.out) / (tree.name + (csv ? ".csv" : ".txt")) : fs::path(o.out);
        const QsmModel model = qsm_from_tree(tree.skeleton, tree.name);
        if (model.cylinders.empty()) throw Error::input(tree.name, "a single-node skeleton has no cylinders to export");
        written.push_back(path.string());
        if (csv) {
            write_qsm_csv(model, path);
            continue;
        }
        write_treeqsm_cylinders(model, path);
        write_qsm_branch_table(model, qsm_branch_table_path(path));
        write_qsm_tree_table(model, qsm_tree_table_path(path));
        written.push_back(qsm_branch_table_path(path).string());
        written.push_back(qsm_tree_table_path(path).string());
    }
    return written;
}

std::vector<std::pair<std::string, double>> extras_of(const TreeSummary& t) {
    const TreeMeasures& m = t.measures;
    std::vector<std::pair<std::string, double>> extras = {
            {"height", m.height}, {"trunkDiameter", m.dbh}, {"crownDiameter", m.crown_diameter}, {"woodVolume", m.wood_volume}};
    if (t.confidence) extras.emplace_back("confidence", *t.confidence);
    return extras;
}

void write_glb(const ExportInput& input, const std::vector<TreeSummary>& summaries, const ExportCliOptions& o) {
    std::vector<GltfTree> trees;
    for (std::size_t i = 0; i < input.trees.size(); ++i) {
        const ExportTree& tree = input.trees[i];
        trees.push_back({tree.name, tree.skeleton.origin, tree_lods(tree, o.geometry), extras_of(summaries[i]), tree.species});
    }
    const Eigen::Vector3d origin = input.trees.front().skeleton.origin;
    write_file_atomically(o.out, glb_bytes(trees, origin));
    write_georef_sidecar(o.out, origin, Georeference{o.crs.empty() ? input.crs : o.crs, {}});
}

void write_mesh_file(const ExportInput& input, const ExportCliOptions& o) {
    TriangleMesh all;
    for (const auto& tree : input.trees) all.append(tree_mesh(tree, o.geometry));
    if (all.faces.empty()) throw Error::input(o.input, "no tree has any geometry to export");
    write_mesh(all, o.out);
    write_georef_sidecar(o.out, all.origin, Georeference{o.crs.empty() ? input.crs : o.crs, {}});
}

nlohmann::json summary_json(const ExportCliOptions& o, const OptionTable& table, const ExportInput& input,
                            const std::vector<TreeSummary>& trees, const std::vector<std::string>& outputs) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& t : trees)
        list.push_back({{"name", t.name},
                        {"height", t.measures.height},
                        {"dbh", t.measures.dbh},
                        {"crown_diameter", t.measures.crown_diameter},
                        {"crown_volume", t.measures.crown_volume},
                        {"wood_volume", t.measures.wood_volume},
                        {"skeleton_length", t.measures.total_length},
                        {"branches", t.measures.branches},
                        {"lobes", t.measures.lobes},
                        {"confidence", t.confidence ? nlohmann::json(*t.confidence) : nlohmann::json()}});
    return {{"treelobes", kVersion},   {"command", "export"},
            {"input", o.input},        {"format", o.format},
            {"options", table.json()}, {"crs", o.crs.empty() ? input.crs : o.crs},
            {"outputs", outputs},      {"trees", list}};
}

int run_export(ExportCliOptions o, const OptionTable& table, const GlobalOptions& global) {
    o.geometry.leaves = !o.no_leaves;
    if (o.cityjson.instances && o.format != "cityjson") throw Error::usage("--instances applies to --format cityjson only");
    const ExportInput input = read_export_input(o.input, o.lod);
    std::vector<TreeSummary> summaries;
    for (const auto& tree : input.trees) summaries.push_back({tree.name, measure_tree(tree), tree.confidence});
    std::vector<std::string> outputs{o.out};
    if (o.format == "qsm-txt" || o.format == "qsm-csv")
        outputs = write_qsm(input, o);
    else if (o.format == "glb")
        write_glb(input, summaries, o);
    else if (o.format == "cityjson")
        write_file_atomically(o.out, cityjson_text(input.trees, o.crs.empty() ? input.crs : o.crs, o.cityjson));
    else
        write_mesh_file(input, o);
    if (global.json) {
        std::cout << summary_json(o, table, input, summaries, outputs).dump(2) << "\n";
        return 0;
    }
    std::printf("%s -> %s (%s): %zu tree%s\n", o.input.c_str(), o.out.c_str(), o.format.c_str(), input.trees.size(),
                input.trees.size() == 1 ? "" : "s");
    for (const auto& t : summaries)
        std::printf("  %s: height %.2f m, DBH %.3f m, crown diameter %.2f m, wood volume %.4f m3\n", t.name.c_str(), t.measures.height,
                    t.measures.dbh, t.measures.crown_diameter, t.measures.wood_volume);
    return 0;
}

}  // namespace

void add_export_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<ExportCliOptions>();
    CLI::App* sub = app.add_subcommand("export", "Write trees as QSM tables, glTF 2.0 (.glb), CityJSON 2.0, PLY or OBJ meshes");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("input", options->input, "Skeleton PLY, .tlobe, .dbf6, .forest, or a folder of them")->required();
    table->add("--format", options->format,
               "ply|obj (branch tubes + lobes), glb (with LODs), cityjson, qsm-txt (TreeQSM cylinder, branch and tree tables), "
               "qsm-csv (SimpleForest/rTwig)")
            ->required()
            ->check(CLI::IsMember({"ply", "obj", "glb", "cityjson", "qsm-txt", "qsm-csv"}));
    table->add("--out", options->out, "Output file (QSM of several trees: a folder of <tree>.txt / <tree>.csv)")->required();
    table->add("--lod", options->lod, "LOD of .dbf6/.forest inputs to export (0 = full detail)")->check(cli::NonNegativeNumber);
    table->add("--lods", options->geometry.lods, "glb: levels of detail (MSFT_lod), 1..8")->check(CLI::Range(1, 8));
    table->add("--sides", options->geometry.sides, "Branch tube sides at full detail, 3..64")->check(CLI::Range(3, 64));
    table->add_flag("--no-leaves", options->no_leaves, "glb: no leaf cards on skeletons without lobes");
    table->add("--leaf-size", options->geometry.leaf_size, "glb: leaf card edge in metres")->check(cli::PositiveNumber);
    table->add_flag("--instances", options->cityjson.instances,
                    "cityjson: LoD 2 as GeometryInstances of one template per species (geometry-templates)");
    table->add("--crs", options->crs, "CRS of the input (EPSG:25832 or WKT) when its georef sidecar has none");
    sub->callback([options, table, &global, &job] { job = [options, table, &global] { return run_export(*options, *table, global); }; });
}

}  // namespace treelobes::cli
