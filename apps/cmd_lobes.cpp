// The lobe stage's two subcommands (Livny et al. 2011, §4.2, §5, §6.2):
// `treelobes lobes INPUT... --out DIR`: skeleton reconstruction, edge confidence, lobe
// clusters, alpha-shape lobes, and per tree DIR/<stem>.tlobe, DIR/<stem>_lobes.ply (all lobes),
// DIR/<stem>_main.ply (main skeleton) and DIR/<stem>_lobes.json (summary). A failing input is
// listed in DIR/failures.jsonl and the others go on (exit 3).
// `treelobes synthesize FILE.tlobe --out MESH`: lobe texturing with the species' patch library,
// the full (or --lod reduced) tree mesh, fidelity metrics against --points and a --preview PNG.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/reconstruction_flags.hpp"
#include "apps/summary_values.hpp"
#include "config/species_profile.hpp"
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "core/version.hpp"
#include "geometry/closed_mesh.hpp"
#include "geometry/mesh_distance.hpp"
#include "lobes/lobe_tree.hpp"
#include "lobes/synthesis.hpp"
#include "lobes/tlobe_io.hpp"
#include "reconstruct/reconstruct_tree.hpp"
#include "render/rasterizer.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
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

struct LobesCliOptions {
    std::vector<std::string> inputs;
    std::string out;
    SpeciesFlags flags;
    ReconstructOptions stage;
    lobes::LobeOptions lobes;
    lobes::TlobeOptions file;
    double budget_kb = 39;  // Livny et al. 2011, Table 2: under 40 kB per tree
};

nlohmann::json lobe_json(const lobes::LobeTree& tree, const lobes::Lobe& lobe) {
    const Eigen::Vector3f seed = tree.seed_position(lobe);
    return {{"points", lobe.points},
            {"vertices", lobe.mesh.vertices.size()},
            {"faces", lobe.mesh.faces.size()},
            {"volume", rounded(lobe.volume(), 5)},
            {"area", rounded(lobe.area(), 4)},
            {"seed",
             {{"node", lobe.seed_node},
              {"position", {rounded(seed.x()), rounded(seed.y()), rounded(seed.z())}},
              {"thickness", rounded(tree.seed_thickness(lobe), 5)},
              {"direction",
               {rounded(lobe.seed_direction.x(), 3), rounded(lobe.seed_direction.y(), 3), rounded(lobe.seed_direction.z(), 3)}}}}};
}

TriangleMesh merged_lobes(const lobes::LobeTree& tree) {
    TriangleMesh all;
    all.origin = tree.skeleton.origin;
    for (const auto& lobe : tree.lobes) {
        TriangleMesh m = lobe.mesh;
        m.origin = tree.skeleton.origin;  // lobes live in the tree's frame
        all.append(m);
    }
    return all;
}

nlohmann::json run_one(const LobesCliOptions& o, const OptionTable& table, const fs::path& input, const GlobalOptions& global) {
    const auto start = std::chrono::steady_clock::now();
    const PointCloud cloud = read_point_cloud(input);
    const TreeReconstruction r = reconstruct_tree(cloud, o.stage, input.string());
    const auto reconstructed = std::chrono::steady_clock::now();
    lobes::LobeReport report;
    const lobes::LobeTree tree = lobes::build_lobe_tree(cloud, r, o.stage, o.flags.species, o.lobes, &report);
    const auto lobed = std::chrono::steady_clock::now();
    const std::string bytes = lobes::encode_tlobe(tree, o.file);
    // Read back what is written: the summary reports the decoded lobes' closedness.
    const lobes::LobeTree decoded = lobes::decode_tlobe(bytes, input.string());
    std::size_t closed = 0;
    for (const auto& lobe : decoded.lobes) closed += check_closed(lobe.mesh).closed() && lobe.volume() > 0 ? 1 : 0;
    const auto coded = std::chrono::steady_clock::now();

    const fs::path dir(o.out);
    const std::string stem = input.stem().string();
    const fs::path tlobe = dir / (stem + ".tlobe"), meshes = dir / (stem + "_lobes.ply"), main = dir / (stem + "_main.ply"),
                   summary_path = dir / (stem + "_lobes.json");
    write_file_atomically(tlobe, bytes);
    if (!tree.lobes.empty()) write_mesh(merged_lobes(tree), meshes);
    write_skeleton_ply(tree.skeleton, main);

    std::size_t faces = 0;
    nlohmann::json lobes_json = nlohmann::json::array();
    double occupancy_cell = 0;  // the grid the file had room for (one for all lobes), 0 = none
    for (std::size_t i = 0; i < tree.lobes.size(); ++i) {
        faces += tree.lobes[i].mesh.faces.size();
        lobes_json.push_back(lobe_json(tree, tree.lobes[i]));
        const lobes::Occupancy& occupancy = decoded.lobes[i].occupancy;
        lobes_json.back()["occupied_cells"] = occupancy.occupied_count();
        occupancy_cell = std::max(occupancy_cell, static_cast<double>(occupancy.cell));
    }
    nlohmann::json seconds = nlohmann::json::object();
    for (const auto& [stage, t] : r.summary.seconds) seconds["reconstruct " + stage] = rounded(t);
    for (const auto& [stage, t] : report.seconds) seconds["lobes " + stage] = rounded(t);
    auto span = [](auto a, auto b) { return rounded(std::chrono::duration<double>(b - a).count()); };
    seconds["reconstruct"] = span(start, reconstructed);
    seconds["lobes"] = span(reconstructed, lobed);
    seconds["encode and verify"] = span(lobed, coded);
    nlohmann::json summary = {
            {"treelobes", kVersion},
            {"input", input.string()},
            {"options", table.json()},
            {"skeleton",
             {{"internodes", r.skeleton.size() > 0 ? r.skeleton.size() - 1 : 0},
              {"main_nodes", tree.skeleton.size()},
              {"root_diameter", rounded(tree.root_diameter, 4)},
              {"low_confidence_edges", report.low_confidence_edges}}},
            {"clusters",
             {{"found", report.clusters},
              {"kept_as_branches_small", report.kept_small},
              {"kept_as_branches_no_shape", report.kept_no_shape}}},
            {"points",
             {{"lobes", report.lobe_points}, {"main", report.main_points}, {"dropped_attached_to_lobes", report.dropped_points_attached}}},
            {"lobe_count", tree.lobes.size()},
            {"closed_lobes", closed},
            {"lobe_faces", faces},
            {"faces_before_simplification", report.faces_before_simplification},
            {"tlobe_bytes", bytes.size()},
            {"occupancy_cell", occupancy_cell > 0 ? nlohmann::json(rounded(occupancy_cell, 4)) : nlohmann::json()},
            {"lobes", lobes_json},
            {"outputs",
             {{"tlobe", tlobe.string()},
              {"lobes", tree.lobes.empty() ? nlohmann::json() : nlohmann::json(meshes.string())},
              {"main_skeleton", main.string()}}},
            {"seconds", seconds}};
    write_file_atomically(summary_path, summary.dump(2) + "\n");
    if (!global.json)
        std::printf("%s: %zu %s (%zu closed, %zu faces), %zu main nodes, %.1f kB .tlobe; reconstruct %.2f s, lobes %.2f s\n",
                    input.string().c_str(), tree.lobes.size(), tree.lobes.size() == 1 ? "lobe" : "lobes", closed, faces,
                    tree.skeleton.size(), bytes.size() / 1000.0, std::chrono::duration<double>(reconstructed - start).count(),
                    std::chrono::duration<double>(lobed - reconstructed).count());
    return summary;
}

int run_lobes(LobesCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    apply_species_flags(o.flags, o.stage);
    o.file.max_bytes = static_cast<std::size_t>(o.budget_kb * 1000);
    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (!fs::is_directory(o.out)) throw Error::usage("--out " + o.out + ": cannot create the output folder");
    nlohmann::json trees = nlohmann::json::array(), failures = nlohmann::json::array();
    std::set<std::string> stems;
    int last_code = 0;
    for (const auto& name : o.inputs) {
        try {
            if (!stems.insert(fs::path(name).stem().string()).second)
                throw Error::input(name, "another input has the same name stem; its outputs would be overwritten");
            trees.push_back(run_one(o, table, name, global));
        } catch (const Error& e) {
            if (e.code() == ExitCode::Usage) throw;
            std::cerr << "treelobes: error: " << e.what() << "\n";
            failures.push_back({{"input", name}, {"reason", e.what()}, {"exit_code", static_cast<int>(e.code())}});
            last_code = static_cast<int>(e.code());
        }
    }
    if (!failures.empty()) {
        std::string lines;
        for (const auto& f : failures) lines += f.dump() + "\n";
        write_file_atomically(fs::path(o.out) / "failures.jsonl", lines);
    }
    if (global.json)
        std::cout << nlohmann::json{{"treelobes", kVersion}, {"command", "lobes"}, {"out", o.out}, {"trees", trees}, {"failures", failures}}
                             .dump(2)
                  << "\n";
    if (failures.empty()) return 0;
    return o.inputs.size() == 1 ? last_code : static_cast<int>(ExitCode::PartialFailure);
}

// ---- synthesize ----------------------------------------------------------------------------

constexpr const char* kDefaultSynthesisSpecies = "lagerstroemia";  // the profile of Livny et al. 2011, Appendix A

struct SynthesizeCliOptions {
    std::string input;
    std::string out;
    std::string species;
    std::string points;
    std::string preview;
    double lod = 1.0;
    lobes::SynthesisOptions synthesis;
};

double percentile(std::vector<float> values, double q) {
    if (values.empty()) return 0.0;
    const auto k = static_cast<std::size_t>(std::llround(q * static_cast<double>(values.size() - 1)));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
}

void write_preview(const fs::path& path, const PointCloud* cloud, const TriangleMesh& wood, const TriangleMesh& leaves) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
    auto grow = [&](const Eigen::Vector3d& p) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    };
    for (const auto* m : {&wood, &leaves})
        for (const auto& v : m->vertices) grow(m->origin + v.cast<double>());
    if (cloud)
        for (std::size_t i = 0; i < cloud->size(); ++i) grow(cloud->global(i));
    if (!(lo.array() <= hi.array()).all()) return;
    const render::View view = render::View::side(lo, hi, 0, 10);
    std::vector<render::Image> panels;
    if (cloud) {
        render::Rasterizer r(600, 800, view);
        r.draw_points(*cloud, {40, 40, 40, 255});
        panels.push_back(r.image());
    }
    render::Rasterizer r(600, 800, view);
    r.draw_mesh(wood, {110, 80, 50, 255});
    r.draw_mesh(leaves, {60, 140, 50, 255});
    panels.push_back(r.image());
    render::write_png(render::side_by_side(panels), path);
}

// The points that belong to the tree, for the fidelity metric: inside the bounding box of the
// lobes and the main skeleton (grown by 25 cm), not classified ground (ASPRS 2) and not more
// than 10 cm below the stem foot. Scans often carry ground far around the tree.
PointCloud points_of_tree(const PointCloud& cloud, const lobes::LobeTree& tree) {
    Eigen::Vector3f lo = tree.skeleton.nodes[0].position, hi = lo;
    for (const auto& node : tree.skeleton.nodes) {
        lo = lo.cwiseMin(node.position);
        hi = hi.cwiseMax(node.position);
    }
    for (const auto& lobe : tree.lobes)
        for (const auto& v : lobe.mesh.vertices) {
            lo = lo.cwiseMin(v);
            hi = hi.cwiseMax(v);
        }
    const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.25);
    Eigen::Vector3d box_lo = tree.skeleton.origin + lo.cast<double>() - margin, box_hi = tree.skeleton.origin + hi.cast<double>() + margin;
    box_lo.z() = tree.skeleton.origin.z() + tree.skeleton.nodes[0].position.z() - 0.1;
    PointCloud out;
    out.origin = cloud.origin;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.classification.empty() && cloud.classification[i] == 2) continue;
        const Eigen::Vector3d p = cloud.global(i);
        if ((p.array() < box_lo.array()).any() || (p.array() > box_hi.array()).any()) continue;
        out.positions.push_back(cloud.positions[i]);
    }
    if (out.empty()) throw Error::input("--points", "no point of the cloud lies in the tree's bounding box");
    return out;
}

int run_synthesize(const SynthesizeCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    const auto start = std::chrono::steady_clock::now();
    const lobes::LobeTree tree = lobes::read_tlobe(o.input);
    std::string species = !o.species.empty() ? o.species : tree.species;
    if (species.empty()) {
        log_warn(o.input + ": no species in the file or on the command line; using " + kDefaultSynthesisSpecies + " patches");
        species = kDefaultSynthesisSpecies;
    }
    const auto profiles = load_species_profiles(default_species_file());
    const SpeciesProfile& profile = find_species_profile(profiles, species);
    std::optional<PointCloud> cloud;
    if (!o.points.empty()) cloud = read_point_cloud(o.points);
    const double read_seconds = seconds_since(start);

    auto mark = std::chrono::steady_clock::now();
    const lobes::TexturedTree textured = lobes::texture_tree(tree, profile, o.synthesis);
    const double texturing_seconds = seconds_since(mark);
    mark = std::chrono::steady_clock::now();
    const lobes::SynthesizedMesh mesh = lobes::synthesized_mesh(tree, textured, o.lod, o.synthesis);
    const double mesh_seconds = seconds_since(mark);
    write_mesh(mesh.combined(), o.out);

    std::size_t instances = 0;
    double filled = 0;
    nlohmann::json per_lobe = nlohmann::json::array();
    for (const auto& lobe : textured.lobes) {
        instances += lobe.instances.size();
        filled += lobe.filled;
        per_lobe.push_back({{"patches", lobe.instances.size()},
                            {"docks_used", lobe.docks_used},
                            {"docks_outside", lobe.docks_outside},
                            {"docks_redundant", lobe.docks_redundant},
                            {"reseeds", lobe.reseeds},
                            {"target_cells", lobe.target_cells},
                            {"filled", rounded(lobe.filled, 3)},
                            {"triangles", lobe.triangles},
                            {"budget_spent", lobe.budget_spent}});
    }
    nlohmann::json summary = {{"treelobes", kVersion},
                              {"input", o.input},
                              {"options", table.json()},
                              {"species", profile.entry.name},
                              {"seed", o.synthesis.texturing.seed},
                              {"lod", o.lod},
                              {"library", {{"branchlets", textured.library.branchlets}, {"patches", textured.library.patches.size()}}},
                              {"lobes", tree.lobes.size()},
                              {"patch_instances", instances},
                              {"mean_lobe_filled", tree.lobes.empty() ? 0.0 : rounded(filled / static_cast<double>(tree.lobes.size()), 3)},
                              {"skeleton_edges", mesh.skeleton_edges},
                              {"twig_segments", mesh.twig_segments},
                              {"leaves", mesh.leaf_count},
                              {"leaf_share", rounded(textured.leaf_share, 3)},
                              {"triangles", mesh.triangles()},
                              {"max_triangles", o.synthesis.max_triangles},
                              {"patch_budget", textured.patch_budget},
                              {"lobe_texturing", per_lobe},
                              {"output", o.out}};
    nlohmann::json seconds = {{"read", rounded(read_seconds)},
                              {"texturing", rounded(texturing_seconds)},
                              {o.lod < 1 ? "lod_extraction" : "meshing", rounded(mesh_seconds)}};
    if (cloud && mesh.triangles() == 0) log_warn(o.input + ": the synthesized mesh is empty; no fidelity metrics");
    if (cloud && mesh.triangles() > 0) {
        mark = std::chrono::steady_clock::now();
        const PointCloud tree_points = points_of_tree(*cloud, tree);
        const MeshDistance distance(mesh.combined());
        const std::vector<float> d = distance.distances(tree_points);
        summary["fidelity"] = {{"points", d.size()},
                               {"median_point_to_mesh", rounded(percentile(d, 0.5))},
                               {"p95_point_to_mesh", rounded(percentile(d, 0.95))}};
        seconds["metrics"] = rounded(seconds_since(mark));
    }
    if (!o.preview.empty()) {
        mark = std::chrono::steady_clock::now();
        write_preview(o.preview, cloud ? &*cloud : nullptr, mesh.wood, mesh.leaves);
        seconds["preview"] = rounded(seconds_since(mark));
        summary["preview"] = o.preview;
    }
    seconds["total"] = rounded(seconds_since(start));
    summary["seconds"] = seconds;
    fs::path summary_path(o.out);
    summary_path.replace_extension(".json");
    write_file_atomically(summary_path, summary.dump(2) + "\n");
    if (global.json) {
        std::cout << summary.dump(2) << "\n";
    } else {
        std::printf("%s: %zu %s textured with %zu %s patches -> %zu triangles (%zu leaves) in %.2f s", o.input.c_str(), tree.lobes.size(),
                    tree.lobes.size() == 1 ? "lobe" : "lobes", instances, profile.entry.name.c_str(), mesh.triangles(), mesh.leaf_count,
                    texturing_seconds + mesh_seconds);
        if (summary.contains("fidelity"))
            std::printf("; input points to mesh: median %.3f m, p95 %.3f m", summary["fidelity"]["median_point_to_mesh"].get<double>(),
                        summary["fidelity"]["p95_point_to_mesh"].get<double>());
        std::printf("\n");
    }
    return 0;
}

}  // namespace

void add_lobes_commands(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto o = std::make_shared<LobesCliOptions>();
    CLI::App* sub =
            app.add_subcommand("lobes", "Lobe-based representation (.tlobe) of single-tree scans: main skeleton + alpha-shape lobes");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("inputs", o->inputs, "Point clouds of single trees (LAS, PLY, PCD, XYZ/CSV)")->required();
    table->add("--out", o->out, "Output folder")->required();
    add_species_flags(*table, o->flags, "Lobe diameter factor f_s of Eq. 2: larger -> more, smaller lobes (default 1.0, or the species')",
                      o->stage);
    table->add("--alpha-factor", o->lobes.alpha.alpha_factor, "alpha = FACTOR * alpha_min (ball radii)")->check(CLI::Range(1.0, 100.0));
    table->add("--min-cluster-points", o->lobes.min_cluster_points, "Smaller clusters stay on the skeleton as branches")
            ->check(CLI::Range(4, 100000));
    table->add("--max-shape-points", o->lobes.max_shape_points, "Larger clusters are thinned on a grid before the alpha shape")
            ->check(CLI::Range(100, 10000000));
    table->add("--dropped-point-reach", o->lobes.dropped_point_reach,
               "Outliers dropped by the reconstruction within this many metres of a lobe's points join its occupancy (0 = off)")
            ->check(CLI::Range(0.0, 10.0));
    table->add("--face-budget", o->lobes.face_budget, "Lobe faces over the whole tree after simplification")
            ->check(CLI::Range(100, 10000000));
    table->add("--quantum", o->file.quantum, "Grid of skeleton positions and occupancy cells in the .tlobe file, metres")
            ->check(CLI::Range(0.0001, 0.1));
    table->add("--lobe-quantum", o->file.lobe_quantum,
               "Grid of lobe surface vertices in the .tlobe file, metres (an eighth of the occupancy cell when that is coarser)")
            ->check(CLI::Range(0.0001, 0.1));
    table->add("--skeleton-tolerance", o->file.skeleton_tolerance,
               "The .tlobe stores the main skeleton without the nodes within this many metres of their chain (0 = every node)")
            ->check(CLI::Range(0.0, 1.0));
    table->add("--bare-twig-length", o->file.bare_twig_length,
               "Where the budget binds, the main skeleton's twigs that seed no lobe, up to this many metres, are left out before "
               "the occupancy grid is coarsened (0 = never)")
            ->check(CLI::Range(0.0, 100.0));
    table->add("--min-points-per-cell", o->file.min_points_per_cell,
               "Occupancy grids finer than this many lobe points per occupied cell are skipped (0 = any grid)")
            ->check(CLI::Range(0.0, 1000.0));
    table->add("--budget-kb", o->budget_kb,
               "Size each .tlobe may take (kB); its lobe surfaces are simplified, then its occupancy grid coarsened, to fit")
            ->check(CLI::Range(2.0, 10000.0));
    sub->callback([o, table, &global, &job] { job = [o, table, &global] { return run_lobes(*o, *table, global); }; });

    auto so = std::make_shared<SynthesizeCliOptions>();
    CLI::App* syn =
            app.add_subcommand("synthesize", "Full tree mesh from a .tlobe: main branches plus lobes textured with species patches");
    auto syn_table = std::make_shared<OptionTable>(syn);
    syn->add_option("input", so->input, "Lobe-based representation (.tlobe) from `treelobes lobes`")->required();
    syn_table->add("--out", so->out, "Output mesh (.ply, .obj, .off); a summary goes next to it as .json")->required();
    syn_table->add("--species", so->species, "Patch library species (default: the file's species, else lagerstroemia)");
    syn_table->add("--seed", so->synthesis.texturing.seed, "Random seed of patch fitting");
    syn_table->add("--library-seed", so->synthesis.library.seed, "Random seed of the species' patch library");
    syn_table->add("--lod", so->lod, "Level of detail: fraction of skeleton edges, twigs and leaves kept (0..1]")
            ->check(CLI::Range(0.001, 1.0));
    syn_table
            ->add("--max-triangles", so->synthesis.max_triangles,
                  "Triangles of the synthesized tree at most (a hard bound): the main branches', the rest shared by the lobes by volume; "
                  "leafy patches are thinned")
            ->check(CLI::Range(1000, 1000000000));
    syn_table
            ->add("--max-lobe-patches", so->synthesis.texturing.max_patches_per_lobe,
                  "Patches per lobe at most (a safety bound; --max-triangles governs)")
            ->check(CLI::Range(1, 10000000));
    syn_table
            ->add("--fill-cell", so->synthesis.texturing.fill_cell,
                  "Smallest edge of the lobe fill cells, metres (cells are sized to the lobe's patch budget)")
            ->check(CLI::Range(0.01, 10.0));
    syn_table
            ->add("--max-fill-cells", so->synthesis.texturing.max_fill_cells, "Fill cells per lobe at most (larger lobes get larger cells)")
            ->check(CLI::Range(1.0, 1e7));
    syn_table->add("--points", so->points, "The input cloud: report the one-sided distance from its points to the mesh");
    syn_table->add("--preview", so->preview, "PNG preview: input points (with --points) next to the synthesized tree");
    syn->callback([so, syn_table, &global, &job] { job = [so, syn_table, &global] { return run_synthesize(*so, *syn_table, global); }; });
}

}  // namespace treelobes::cli
