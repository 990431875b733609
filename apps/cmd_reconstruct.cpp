// `treelobes reconstruct INPUT... --out DIR`: one skeleton, branch mesh, labelled points and
// summary per single-tree scan (Livny et al. 2011, §4.1). Trees are independent: a failing
// input is listed in DIR/failures.jsonl and the others go on (exit 3). Finished trees are
// skipped on a re-run unless --overwrite.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/reconstruction_flags.hpp"
#include "apps/summary_values.hpp"
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "core/version.hpp"
#include "geometry/branch_mesh.hpp"
#include "reconstruct/reconstruct_tree.hpp"

#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <set>

namespace fs = std::filesystem;

namespace treelobes::cli {

namespace {

struct ReconstructCliOptions {
    std::vector<std::string> inputs;
    std::string out;
    SpeciesFlags flags;
    std::string mesh_format = "ply";
    bool overwrite = false;
    bool reject_non_trees = false;
    std::string outlier_test = "auto";
    ReconstructOptions stage;
    BranchMeshOptions mesh;
};

struct TreeOutputs {
    fs::path skeleton, branches, points, summary;
};

TreeOutputs outputs_for(const ReconstructCliOptions& o, const fs::path& input) {
    const fs::path dir(o.out);
    const std::string stem = input.stem().string();
    return {dir / (stem + "_skeleton.ply"), dir / (stem + "_branches." + o.mesh_format), dir / (stem + "_points.ply"),
            dir / (stem + "_summary.json")};
}

// Every flag's value; the bin width and internode length as worked out from the scan when their
// flags leave them at 0.
nlohmann::json options_json(const OptionTable& table, const TreeSummary& s) {
    nlohmann::json options = table.json();
    options["bin_width"] = rounded(s.bin_width);
    options["internode_length"] = rounded(s.internode_length);
    return options;
}

nlohmann::json summary_json(const ReconstructCliOptions& o, const OptionTable& table, const fs::path& input, const TreeOutputs& out,
                            const TreeReconstruction& r) {
    const TreeSummary& s = r.summary;
    nlohmann::json seconds = nlohmann::json::object();
    double total = 0;
    for (const auto& [stage, t] : s.seconds) {
        seconds[stage] = rounded(t);
        total += t;
    }
    seconds["total"] = rounded(total);
    return {{"treelobes", kVersion},
            {"input", input.string()},
            {"options", options_json(table, s)},
            {"points",
             {{"input", s.input_points},
              {"used", s.used_points},
              {"duplicates", s.duplicates},
              {"outliers", s.outliers},
              {"ground", s.ground_points},
              {"beyond_gaps", s.detached_points},
              {"outlier_test", o.stage.preprocess.outlier_neighbours == 0 ? "off"
                               : s.local_outlier_test                     ? "local"
                                                                          : "global"},
              {"linear_fraction", s.linear_fraction < 0 ? nlohmann::json() : nlohmann::json(rounded(s.linear_fraction, 3))}}},
            {"tree",
             {{"height", rounded(s.height, 3)},
              {"dbh", s.dbh_fitted ? nlohmann::json(rounded(s.dbh, 3)) : nlohmann::json()},
              {"root_diameter", rounded(s.root_diameter, 3)},
              {"root_diameter_source", s.root_diameter_source},
              {"crown_width", rounded(s.crown_width, 3)},
              {"total_branch_length", rounded(s.total_length, 3)},
              {"branches", s.branches},
              {"internodes", s.internodes},
              {"recentred_nodes", s.recentred_nodes},
              {"cylinder_axis_nodes", s.cylinder_axis_nodes},
              {"tips", s.tips},
              {"max_branch_order", s.max_branch_order},
              {"stem_visible", s.stem_visible},
              {"ground_removed", s.ground_removed}}},
            {"graph",
             {{"spacing", rounded(s.spacing)},
              {"components", s.graph_components},
              {"bridges", s.bridges},
              {"longest_bridge", rounded(s.longest_bridge)}}},
            {"quality",
             {{"not_a_tree", s.quality.not_a_tree},
              {"planar_fraction", rounded(s.quality.planar_fraction, 3)},
              {"flags", s.quality.flags}}},
            {"outputs", {{"skeleton", out.skeleton.string()}, {"branches", out.branches.string()}, {"points", out.points.string()}}},
            {"seconds", seconds},
            {"peak_memory_mb", rounded(peak_memory_mb(), 1)}};
}

void write_points(const PointCloud& cloud, const TreeReconstruction& r, const fs::path& path) {
    PointCloud labelled = cloud;
    auto& internode = labelled.add_extra("internode", AttributeType::Int32);
    internode.values.assign(r.point_internode.begin(), r.point_internode.end());
    auto& geodesic = labelled.add_extra("geodesic", AttributeType::Float32);
    geodesic.values.assign(r.point_geodesic.begin(), r.point_geodesic.end());
    write_point_cloud(labelled, path);
}

void print_human(const fs::path& input, const TreeSummary& s, double seconds) {
    std::printf("%s: %zu points -> %zu internodes, %zu branches, %.1f m of branches; height %.2f m, ", input.string().c_str(),
                s.input_points, s.internodes, s.branches, s.total_length, s.height);
    if (s.dbh_fitted)
        std::printf("DBH %.3f m", s.dbh);
    else
        std::printf("DBH n/a");
    std::printf(", crown %.2f m, %.2f s\n", s.crown_width, seconds);
    if (!s.quality.flags.empty()) {
        std::printf("  flags:");
        for (const auto& f : s.quality.flags) std::printf(" %s", f.c_str());
        std::printf("%s\n", s.quality.not_a_tree ? "  (this does not look like a tree)" : "");
    }
}

// Runs one input; returns its summary. Throws treelobes::Error for bad input.
nlohmann::json run_one(const ReconstructCliOptions& o, const OptionTable& table, const fs::path& input, const TreeOutputs& out,
                       const GlobalOptions& global) {
    const auto start = std::chrono::steady_clock::now();
    const PointCloud cloud = read_point_cloud(input);
    TreeReconstruction r = reconstruct_tree(cloud, o.stage, input.string());
    if (o.reject_non_trees && r.summary.quality.not_a_tree)
        throw Error::input(input.string(), "not a tree: " + std::to_string(r.summary.quality.planar_fraction) +
                                                   " of the points lie on wide planes (drop --reject-non-trees to keep it)");
    auto mark = std::chrono::steady_clock::now();
    const TriangleMesh mesh = build_branch_mesh(r.skeleton, o.mesh);
    r.summary.seconds.emplace_back("mesh", seconds_since(mark));
    mark = std::chrono::steady_clock::now();
    write_skeleton_ply(r.skeleton, out.skeleton);
    write_mesh(mesh, out.branches);
    write_points(cloud, r, out.points);
    r.summary.seconds.emplace_back("write", seconds_since(mark));
    nlohmann::json summary = summary_json(o, table, input, out, r);
    write_file_atomically(out.summary, summary.dump(2) + "\n");  // last: its presence marks a finished tree
    if (!global.json) print_human(input, r.summary, seconds_since(start));
    return summary;
}

int run_reconstruct(ReconstructCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    std::unique_ptr<tbb::global_control> threads;
    if (global.threads > 0)
        threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                        static_cast<std::size_t>(global.threads));
    apply_species_flags(o.flags, o.stage);
    o.stage.preprocess.outlier_test = parse_outlier_test(o.outlier_test);
    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (!fs::is_directory(o.out)) throw Error::usage("--out " + o.out + ": cannot create the output folder");

    nlohmann::json trees = nlohmann::json::array(), failures = nlohmann::json::array(), skipped = nlohmann::json::array();
    std::set<std::string> stems;
    int last_code = 0;
    for (const auto& name : o.inputs) {
        const fs::path input(name);
        const TreeOutputs out = outputs_for(o, input);
        try {
            if (!stems.insert(input.stem().string()).second)
                throw Error::input(name, "another input has the same name stem; its outputs would be overwritten");
            if (!o.overwrite && fs::exists(out.summary) && fs::exists(out.skeleton) && fs::exists(out.branches) && fs::exists(out.points)) {
                log_info(name + ": already reconstructed in " + o.out + " (use --overwrite to redo)");
                skipped.push_back(name);
                continue;
            }
            trees.push_back(run_one(o, table, input, out, global));
        } catch (const Error& e) {
            if (e.code() == ExitCode::Usage) throw;  // a bad option fails every tree alike
            std::cerr << "treelobes: error: " << e.what() << "\n";
            failures.push_back({{"input", name}, {"reason", e.what()}, {"exit_code", static_cast<int>(e.code())}});
            last_code = static_cast<int>(e.code());
        } catch (const std::exception& e) {
            std::cerr << "treelobes: internal error on " << name << ": " << e.what() << "\n";
            failures.push_back({{"input", name},
                                {"reason", std::string("internal error: ") + e.what()},
                                {"exit_code", static_cast<int>(ExitCode::Internal)}});
            last_code = static_cast<int>(ExitCode::Internal);
        }
    }
    if (!failures.empty()) {
        std::string lines;
        for (const auto& f : failures) lines += f.dump() + "\n";
        write_file_atomically(fs::path(o.out) / "failures.jsonl", lines);
    }
    if (global.json)
        std::cout << nlohmann::json{{"treelobes", kVersion}, {"command", "reconstruct"}, {"out", o.out},
                                    {"trees", trees},        {"skipped", skipped},       {"failures", failures}}
                             .dump(2)
                  << "\n";
    else
        std::printf("reconstructed %zu of %zu input(s) into %s (%zu failed, %zu skipped)\n", trees.size(), o.inputs.size(), o.out.c_str(),
                    failures.size(), skipped.size());
    if (failures.empty()) return 0;
    return o.inputs.size() == 1 ? last_code : static_cast<int>(ExitCode::PartialFailure);
}

void add_flags(CLI::App* sub, OptionTable& table, ReconstructCliOptions& o) {
    sub->add_option("inputs", o.inputs, "Point clouds of single trees (LAS, PLY, PCD, XYZ/CSV)")->required();
    table.add("--out", o.out, "Output folder")->required();
    add_species_flags(table, o.flags, "Lobe diameter factor f_s of Eq. 2 (default 1.0, or the species')", o.stage);
    auto& k = o.stage.skeleton;
    table.add("--neighbours", k.neighbours, "k of the neighbour graph")->check(CLI::Range(2, 64));
    table.add("--bin-width", k.bin_width, "Geodesic bin width in metres (0 = 2.5 x the point sampling distance, kept within 0.02..0.5)")
            ->check(cli::NonNegativeNumber);
    table.add("--internode-length", k.internode_length, "Skeleton internode length in metres (0 = the bin width)")
            ->check(cli::NonNegativeNumber);
    table.add("--min-twig-length", k.min_twig_length, "Prune leaf branches shorter than this, metres (0 = two bins)")
            ->check(cli::NonNegativeNumber);
    table.add("--smoothing", k.smoothing_iterations, "Smoothing passes over the skeleton")->check(CLI::Range(0, 100));
    table.add("--geodesic-smoothing", k.geodesic_smoothing, "Neighbour-averaging passes over the geodesic field before binning")
            ->check(CLI::Range(0, 50));
    table.add("--max-gap", k.max_gap, "Leave parts joined only across a longer gap (metres) out of the skeleton (0 = keep all)")
            ->check(cli::NonNegativeNumber);
    table.add("--max-gap-points", k.max_gap_points, "With --max-gap: leave out only parts of fewer points (0 = any size)")
            ->check(cli::NonNegativeNumber);
    table.add("--bridge-direction", k.bridge_direction,
              "Weight of the angle between a gap bridge and its piece's own axis (0 = shortest bridges)")
            ->check(cli::NonNegativeNumber);
    table.add("--fit-axes", k.fit_axes, "Centre wide branch slices on fitted circles (true/false)");
    table.add("--recentre", o.stage.recentre.enabled,
              "Move thin internodes across onto the centroid of their own points (true/false): on leafy scans the "
              "skeleton otherwise runs beside branches hidden in foliage");
    table.add("--recentre-max-spread", o.stage.recentre.max_spread,
              "Internodes whose points spread wider than this (RMS around their centroid, metres) are thick and stay put")
            ->check(cli::PositiveNumber);
    table.add("--recentre-inside-band", o.stage.recentre.inside_band,
              "Nodes closer to their points' centroid than this many spreads are inside their branch and stay put")
            ->check(cli::NonNegativeNumber);
    auto& c = o.stage.cylinder_axes;
    table.add("--cylinder-axes", c.enabled,
              "Move nodes onto the axes of least-squares cylinders fitted to stretches of branch (true/false): sparse "
              "one-sided scans see only the scanner-facing arc of a branch, whose centroid lies off the axis. Off by "
              "default: it lowers the WoodSKE medians but raises archi tree1's against TreeQSM");
    table.add("--cylinder-window", c.window, "Metres of branch whose points one cylinder is fitted to")->check(cli::PositiveNumber);
    table.add("--cylinder-min-points", c.min_points, "Stretches with fewer points keep their nodes")->check(CLI::Range(6, 100000));
    table.add("--cylinder-max-rms", c.max_rms, "Fits whose RMS residual exceeds this many radii are not trusted")
            ->check(cli::PositiveNumber);
    table.add("--cylinder-min-spread", c.min_spread,
              "Fits wider than the points' cross-section spread (RMS about each internode's centroid) over this many "
              "radii are not trusted: a bent twig fits a wide cylinder")
            ->check(cli::NonNegativeNumber);
    table.add("--root-diameter", o.stage.root_diameter, "Stem diameter at the base in metres (0 = from the stem fit)")
            ->check(cli::NonNegativeNumber);
    table.add("--voxel-size", o.stage.preprocess.voxel_size, "Keep one point per voxel of this size in metres (0 = off)")
            ->check(cli::NonNegativeNumber);
    table.add("--outlier-neighbours", o.stage.preprocess.outlier_neighbours, "k of the outlier filter (0 = off)")->check(CLI::Range(0, 64));
    table.add("--outlier-test", o.outlier_test,
              "Outlier test: global (mean k-NN distance beyond the scan's mean + --outlier-sigma deviations), local "
              "(beyond --outlier-ratio times the neighbours' own: keeps the sparse twigs of leafy TLS scans), auto "
              "(local when few points have linear neighbourhoods, as in leafy crowns)")
            ->check(CLI::IsMember({"auto", "global", "local"}));
    table.add("--outlier-ratio", o.stage.preprocess.outlier_ratio,
              "Local outlier test: drop points whose mean k-NN distance exceeds this many times their neighbours' own")
            ->check(cli::PositiveNumber);
    table.add("--outlier-sigma", o.stage.preprocess.outlier_sigma,
              "Global outlier test: drop points whose mean k-NN distance exceeds the scan's mean + this many "
              "standard deviations")
            ->check(cli::PositiveNumber);
    table.add("--mesh-sides", o.mesh.sides, "Vertices per ring of the branch mesh")->check(CLI::Range(3, 64));
    table.add("--mesh-subdivisions", o.mesh.subdivisions, "Rings per internode of the branch mesh")->check(CLI::Range(1, 16));
    table.add("--mesh-format", o.mesh_format, "Branch mesh format")->check(CLI::IsMember({"ply", "obj", "off"}));
    table.add_flag("--overwrite", o.overwrite, "Redo trees whose outputs exist");
    table.add_flag("--reject-non-trees", o.reject_non_trees, "Fail inputs flagged as not a tree instead of only flagging them");
}

}  // namespace

void add_reconstruct_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<ReconstructCliOptions>();
    CLI::App* sub = app.add_subcommand("reconstruct", "Skeleton, radii, branch mesh and summary of single-tree scans");
    auto table = std::make_shared<OptionTable>(sub);
    add_flags(sub, *table, *options);
    sub->callback(
            [options, table, &global, &job] { job = [options, table, &global] { return run_reconstruct(*options, *table, global); }; });
}

}  // namespace treelobes::cli
