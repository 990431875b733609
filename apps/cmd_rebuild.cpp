// `treelobes rebuild MESH --out DIR`: a heavy polygonal tree (a CG model: bark and leaf
// triangles) in, a light lobe-based tree out (Livny et al. 2011, §7: Xfrog models sampled into
// points and rebuilt, 60 kB instead of 56 MB). The mesh is labelled wood/leaf per face
// (synth/mesh_labels.hpp), sampled (synth/mesh_sampling.hpp), reconstructed, turned into lobes,
// stored as .tlobe (and its skeleton as .dbf6) and synthesized back from the .tlobe; report.json
// compares the rebuilt tree with the original (docs/rebuild.md).
#include "apps/command.hpp"
#include "apps/mesh_fidelity.hpp"
#include "apps/option_table.hpp"
#include "apps/reconstruction_flags.hpp"
#include "apps/summary_values.hpp"
#include "classify/features.hpp"
#include "classify/jointboost.hpp"
#include "config/species_library.hpp"
#include "config/species_profile.hpp"
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "core/version.hpp"
#include "encode/tree_file.hpp"
#include "lobes/lobe_tree.hpp"
#include "lobes/synthesis.hpp"
#include "lobes/tlobe_io.hpp"
#include "reconstruct/reconstruct_tree.hpp"
#include "render/rasterizer.hpp"
#include "synth/mesh_labels.hpp"
#include "synth/mesh_sampling.hpp"

#include <nlohmann/json.hpp>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

namespace fs = std::filesystem;

namespace treelobes::cli {

namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

// --species auto without a --model: the reconstruction keeps its generic parameters
// (beta = gamma = 1.5, f_s = 1) and the lobes are textured with this species' patches, the
// profile of Livny et al. 2011, Appendix A (as `treelobes synthesize` does for a file without species).
constexpr const char* kDefaultPatchSpecies = "lagerstroemia";
constexpr double kMinBudgetBytes = 2000;  // a skeleton and a few coarse lobes

struct RebuildCliOptions {
    std::string input;
    std::string out;
    SpeciesFlags flags;
    std::string model;
    std::string scan = "uniform";
    std::size_t samples = 200000;
    double density = 0;
    int stations = 4;
    std::uint64_t seed = 1;
    double budget_kb = 60;   // Livny et al. 2011, §7: 60 kB for a 56 MB Xfrog tree
    double min_ratio = 500;  // the rebuild job's size target against the input mesh file; 0 = none
    std::string leaf_materials;
    double dbf6_resolution = 5.0;
    std::size_t compare_samples = 20000;
    int image_height = 800;
    ReconstructOptions stage;
    lobes::LobeOptions lobes;
    lobes::SynthesisOptions synthesis;
};

// Wall time per stage, in the order they ran.
class StageClock {
public:
    // `stage` names the time in the report; `doing` is the progress line on stderr.
    void start(const std::string& stage, const std::string& doing) {
        stop();
        log_info("rebuild: " + doing);
        current_ = stage;
        since_ = Clock::now();
    }
    void stop() {
        if (current_.empty()) return;
        seconds_[current_] = rounded(std::chrono::duration<double>(Clock::now() - since_).count(), 3);
        current_.clear();
    }
    json seconds() const { return seconds_; }

private:
    std::string current_;
    Clock::time_point since_;
    json seconds_ = json::object();
};

TriangleMesh faces_labelled(const TriangleMesh& mesh, const std::vector<std::uint8_t>& wood, std::uint8_t want) {
    TriangleMesh part;
    part.origin = mesh.origin;
    part.vertices = mesh.vertices;
    for (std::size_t f = 0; f < mesh.faces.size(); ++f)
        if (wood[f] == want) part.faces.push_back(mesh.faces[f]);
    return part;
}

// The species: given, from the classifier (--model), or the documented default.
struct SpeciesChoice {
    std::string reconstruction;  // empty: generic parameters
    std::string patches;
    std::string source;      // "given", "classifier", "default"
    double probability = 0;  // classifier only
};

SpeciesChoice choose_species(const RebuildCliOptions& o, const PointCloud& samples) {
    if (o.flags.species != "auto") return {o.flags.species, o.flags.species, "given", 0};
    if (o.model.empty()) return {"", kDefaultPatchSpecies, "default", 0};
    const classify::JointBoostModel model = classify::load_jointboost(o.model);
    const std::vector<double> all = classify::compute_features(samples, {}, o.input);
    const std::vector<std::string> names = classify::feature_names();
    std::vector<double> row;
    for (const auto& wanted : model.feature_names) {
        const auto it = std::find(names.begin(), names.end(), wanted);
        if (it == names.end()) throw Error::input(o.model, "model feature '" + wanted + "' is not computed by this version");
        row.push_back(all[static_cast<std::size_t>(it - names.begin())]);
    }
    const std::vector<double> p = model.probabilities(row.data());
    const auto best = static_cast<std::size_t>(std::max_element(p.begin(), p.end()) - p.begin());
    const std::string name = find_species(load_species_entries(default_species_file()), model.classes[best]).name;
    return {name, name, "classifier", p[best]};
}

// original | samples | rebuilt, one camera framing the original (side view, 10 degrees up).
void write_comparison_png(const fs::path& path, const TriangleMesh& original, const std::vector<std::uint8_t>& wood,
                          const PointCloud& samples, const lobes::SynthesizedMesh& rebuilt, const Eigen::Vector3d& lo,
                          const Eigen::Vector3d& hi, int height) {
    const render::View view = render::View::side(lo, hi, 0, 10);
    const double across = std::max(hi.x() - lo.x(), hi.y() - lo.y()), tall = std::max(1e-6, hi.z() - lo.z());
    const int width = std::clamp(static_cast<int>(height * across / tall * 1.05), height / 4, 2 * height);
    const render::Rgba bark{110, 75, 45, 255}, leaf{70, 140, 50, 255};
    render::Rasterizer a(width, height, view), b(width, height, view), c(width, height, view);
    a.draw_mesh(faces_labelled(original, wood, 1), bark);
    a.draw_mesh(faces_labelled(original, wood, 0), leaf);
    std::vector<Eigen::Vector3d> points;
    std::vector<render::Rgba> colours;
    const ExtraAttribute* labels = samples.extra("wood");
    for (std::size_t i = 0; i < samples.size(); ++i) {
        points.push_back(samples.global(i));
        colours.push_back(labels && labels->values[i] > 0.5 ? render::Rgba{120, 70, 30, 255} : render::Rgba{60, 150, 60, 255});
    }
    b.draw_points(points, colours, 1);
    c.draw_mesh(rebuilt.wood, bark);
    c.draw_mesh(rebuilt.leaves, leaf);
    render::write_png(render::side_by_side({a.image(), b.image(), c.image()}), path);
}

// User plus system CPU time of this process so far (all threads).
double cpu_seconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
    return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

std::uintmax_t file_bytes(const fs::path& path) {
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    return ec ? 0 : size;
}

// The .tlobe budget: --budget-kb, or the input file's size / --min-ratio where that is less (never
// under the 2 kB that --budget-kb allows at least).
lobes::TlobeOptions file_options_for(const RebuildCliOptions& o, std::uintmax_t input_bytes) {
    lobes::TlobeOptions file;
    double budget = o.budget_kb * 1000;
    if (o.min_ratio > 0) budget = std::min(budget, std::max(kMinBudgetBytes, static_cast<double>(input_bytes) / o.min_ratio));
    file.max_bytes = static_cast<std::size_t>(budget);
    return file;
}

void print_summary(const json& r) {
    const json& s = r["sizes"];
    const json& f = r["fidelity"];
    std::printf("%s -> %s\n", r["input"].get<std::string>().c_str(), r["out"].get<std::string>().c_str());
    std::printf("  mesh     %.2f MB, %zu triangles (%zu wood, %zu leaf)\n", s["original_bytes"].get<double>() / 1e6,
                r["input_mesh"]["triangles"].get<std::size_t>(), r["input_mesh"]["labels"]["wood_faces"].get<std::size_t>(),
                r["input_mesh"]["labels"]["leaf_faces"].get<std::size_t>());
    std::printf("  samples  %zu (%s), species %s (%s)\n", r["samples"]["points"].get<std::size_t>(),
                r["samples"]["pattern"].get<std::string>().c_str(), r["species"]["patches"].get<std::string>().c_str(),
                r["species"]["source"].get<std::string>().c_str());
    std::printf("  .tlobe   %.1f kB (%.0fx smaller; budget %.1f kB%s), .dbf6 %.1f kB, %zu lobes\n", s["tlobe_bytes"].get<double>() / 1e3,
                s["compression_factor"].get<double>(), s["budget_bytes"].get<double>() / 1e3,
                s["within_budget"].get<bool>() ? "" : ", exceeded: the skeleton and simplest lobes need more",
                s["dbf6_bytes"].get<double>() / 1e3, r["lobes"]["count"].get<std::size_t>());
    const json& cell = s["tlobe_occupancy_cell_m"];
    const std::size_t derived = s["tlobe_surfaces_from_occupancy"].get<std::size_t>();
    std::printf("           lobes stored with %zu of their %zu faces%s, %s\n", s["tlobe_lobe_faces"].get<std::size_t>(),
                r["lobes"]["faces"].get<std::size_t>(),
                derived == 0 ? "" : (" (" + std::to_string(derived) + " surfaces derived from the occupancy)").c_str(),
                cell.is_null() ? "no occupancy (no room in the budget)"
                               : ("occupancy on " + std::to_string(std::lround(100 * cell.get<double>())) + " cm cells").c_str());
    std::printf("  rebuilt  %zu triangles; distance mean %.3f m (%.2f %% of the diagonal), p95 %.3f m, Hausdorff %.3f m\n",
                r["rebuilt"]["triangles"].get<std::size_t>(), f["symmetric"]["mean"].get<double>(),
                100 * f["symmetric"]["mean_of_diagonal"].get<double>(), f["symmetric"]["p95"].get<double>(),
                f["symmetric"]["max"].get<double>());
    print_silhouettes(f);
    std::printf("  leaf area %.1f -> %.1f m^2\n", f["leaf_area"]["original_m2"].get<double>(), f["leaf_area"]["rebuilt_m2"].get<double>());
    std::printf("  %.1f s (%.1f s CPU), peak memory %.0f MB\n", r["seconds"]["total"].get<double>(), r["seconds"]["cpu"].get<double>(),
                r["peak_memory_mb"].get<double>());
}

int run_rebuild(RebuildCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    const auto started = Clock::now();
    StageClock clock;
    // Options first: a usage error must not wait for a big mesh to be read.
    synth::MeshSamplingOptions sampling;
    sampling.pattern = synth::parse_sample_pattern(o.scan);
    sampling.samples = o.samples;
    sampling.density = o.density;
    sampling.stations = o.stations;
    sampling.seed = o.seed;
    if (o.density > 0 && sampling.pattern != synth::SamplePattern::Uniform)
        throw Error::usage("--density is for --scan uniform; scans take --samples");
    synth::MeshLabelOptions labelling;
    if (!o.leaf_materials.empty()) {
        labelling.leaf_words = synth::parse_word_list(o.leaf_materials);
        if (labelling.leaf_words.empty()) throw Error::usage("--leaf-materials needs at least one name");
        labelling.named_faces_default_to_wood = true;
    }
    const std::string species_flag = o.flags.species.empty() ? "auto" : o.flags.species;
    if (species_flag != "auto") o.flags.species = find_species(load_species_entries(default_species_file()), species_flag).name;
    if (!o.model.empty() && species_flag != "auto") throw Error::usage("--model chooses the species for --species auto; drop one of them");
    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (!fs::is_directory(o.out)) throw Error::usage("--out " + o.out + ": cannot create the output folder");
    const fs::path input(o.input), dir(o.out);
    const std::string stem = input.stem().string();
    const lobes::TlobeOptions file_options = file_options_for(o, file_bytes(input));

    clock.start("read", "reading " + o.input);
    const NamedMesh named = read_named_mesh(input);
    if (named.mesh.faces.empty()) throw Error::input(o.input, "the mesh has no triangles");
    clock.start("label", "labelling wood and leaves");
    synth::MeshLabelReport label_report;
    const std::vector<std::uint8_t> wood = synth::label_faces(named, labelling, &label_report);
    const TriangleMesh& original = named.mesh;
    const auto [lo, hi] = world_bounds(original);
    const double diagonal = (hi - lo).norm();
    if (!(diagonal > 0)) throw Error::input(o.input, "the mesh has no extent (every vertex at one place)");

    clock.start("sample", std::string("sampling (") + synth::sample_pattern_name(sampling.pattern) + ")");
    synth::MeshSamplingReport sample_report;
    PointCloud samples;
    try {
        samples = synth::sample_mesh(original, wood, sampling, &sample_report);
    } catch (const Error& e) {
        if (e.code() != ExitCode::InvalidInput) throw;
        throw Error::input(o.input, e.what());
    }
    clock.start("species", "choosing the species");
    const SpeciesChoice species = choose_species(o, samples);
    o.flags.species = species.reconstruction;
    apply_species_flags(o.flags, o.stage);

    clock.start("reconstruct", "reconstructing the skeleton");
    const TreeReconstruction reconstruction = reconstruct_tree(samples, o.stage, o.input);
    clock.start("lobes", "building the lobes");
    lobes::LobeReport lobe_report;
    o.lobes.leaf_label_attribute = "wood";  // the samples' labels from the mesh's own materials: each lobe keeps its leaf share
    lobes::LobeTree tree = lobes::build_lobe_tree(samples, reconstruction, o.stage, species.reconstruction, o.lobes, &lobe_report);
    tree.leaf_area_m2 = label_report.leaf_area;  // the light tree gives the original's leaf area back
    clock.start("encode", "encoding .tlobe and .dbf6");
    const std::string tlobe_bytes = lobes::encode_tlobe(tree, file_options);
    const fs::path tlobe_path = dir / (stem + ".tlobe"), dbf6_path = dir / (stem + ".dbf6"), skeleton_path = dir / (stem + "_skeleton.ply"),
                   mesh_path = dir / (stem + "_rebuilt.ply"), samples_path = dir / (stem + "_samples.ply"),
                   png_path = dir / (stem + "_compare.png"), crowns_path = dir / (stem + "_crowns.png"), report_path = dir / "report.json";
    write_file_atomically(tlobe_path, tlobe_bytes);
    encode::TreeFileOptions dbf6_options;
    dbf6_options.encode.resolution = o.dbf6_resolution;
    encode::write_tree_file(encode::store_tree(reconstruction.skeleton, dbf6_options, o.input), dbf6_path);
    write_skeleton_ply(reconstruction.skeleton, skeleton_path);
    write_point_cloud(samples, samples_path);

    // The light tree as a user gets it back: decoded from the .tlobe bytes, then synthesized.
    clock.start("synthesize", "synthesizing the tree from the .tlobe");
    const lobes::LobeTree stored = lobes::decode_tlobe(tlobe_bytes, tlobe_path.string());
    const auto profiles = load_species_profiles(default_species_file());
    const SpeciesProfile& profile = find_species_profile(profiles, species.patches);
    o.synthesis.texturing.seed = o.seed;
    const lobes::TexturedTree textured = lobes::texture_tree(stored, profile, o.synthesis);
    const lobes::SynthesizedMesh rebuilt = lobes::synthesized_mesh(stored, textured, 1.0, o.synthesis);
    const TriangleMesh rebuilt_all = rebuilt.combined();
    if (rebuilt_all.faces.empty()) throw Error::input(o.input, "the rebuilt tree has no triangles (too few samples on the tree?)");
    write_mesh(rebuilt_all, mesh_path);

    clock.start("compare", "comparing the rebuilt tree with the original");
    MeshFidelityOptions fidelity_options;
    fidelity_options.samples = o.compare_samples;
    fidelity_options.seed = o.seed;
    render::Image crowns;
    json fidelity = mesh_fidelity(original, rebuilt_all, fidelity_options, &crowns);
    const double rebuilt_leaf_area = rebuilt.leaves.area();
    fidelity["leaf_area"] = {{"original_m2", rounded(label_report.leaf_area, 3)},
                             {"rebuilt_m2", rounded(rebuilt_leaf_area, 3)},
                             {"ratio", label_report.leaf_area > 0 ? json(rounded(rebuilt_leaf_area / label_report.leaf_area, 4)) : json()}};
    clock.start("draw", "drawing " + png_path.filename().string());
    write_comparison_png(png_path, original, wood, samples, rebuilt, lo, hi, o.image_height);
    render::write_png(crowns, crowns_path);
    clock.stop();

    const double original_bytes = static_cast<double>(file_bytes(input));
    const double dbf6_bytes = static_cast<double>(file_bytes(dbf6_path));
    std::size_t lobe_faces = 0, stored_lobe_faces = 0;
    for (const auto& lobe : tree.lobes) lobe_faces += lobe.mesh.faces.size();
    std::size_t derived_surfaces = 0;
    for (const auto& lobe : stored.lobes) {
        if (lobe.surface_from_occupancy)
            ++derived_surfaces;
        else
            stored_lobe_faces += lobe.mesh.faces.size();
    }
    // What the budget left of the lobes (docs/tlobe.md): their surfaces' faces and the cell of
    // their occupancy, which all lobes of a file share (none when the budget had no room).
    const json occupancy_cell = stored.lobes.empty() || stored.lobes.front().occupancy.empty()
                                        ? json()
                                        : json(rounded(stored.lobes.front().occupancy.cell, 3));
    json seconds = clock.seconds();
    seconds["total"] = rounded(seconds_since(started), 3);
    seconds["cpu"] = rounded(cpu_seconds(), 3);  // all threads; on a busy machine a steadier figure than the wall time
    json report = {{"treelobes", kVersion},
                   {"command", "rebuild"},
                   {"input", o.input},
                   {"out", o.out},
                   {"options", table.json()},
                   {"input_mesh",
                    {{"format", named.report.format},
                     {"bytes", original_bytes},
                     {"vertices", original.vertices.size()},
                     {"triangles", original.faces.size()},
                     {"polygons_split", named.report.polygons_split},
                     {"degenerate_faces_dropped", named.report.degenerate_faces},
                     {"normals_ignored", named.report.normals_ignored},
                     {"primitives_skipped", named.report.primitives_skipped},
                     {"named_parts", named.names.size()},
                     {"origin", {original.origin.x(), original.origin.y(), original.origin.z()}},
                     {"bbox_diagonal_m", rounded(diagonal, 4)},
                     {"area_m2", rounded(sample_report.surface_area, 3)},
                     {"labels",
                      {{"wood_faces", label_report.wood_by_name + label_report.wood_by_geometry},
                       {"leaf_faces", label_report.leaf_by_name + label_report.leaf_by_geometry},
                       {"wood_by_name", label_report.wood_by_name},
                       {"leaf_by_name", label_report.leaf_by_name},
                       {"wood_by_geometry", label_report.wood_by_geometry},
                       {"leaf_by_geometry", label_report.leaf_by_geometry},
                       {"geometry_parts", label_report.parts},
                       {"leaf_parts", label_report.leaf_parts},
                       {"wood_area_m2", rounded(label_report.wood_area, 3)},
                       {"leaf_area_m2", rounded(label_report.leaf_area, 3)}}}}},
                   {"samples",
                    {{"pattern", synth::sample_pattern_name(sampling.pattern)},
                     {"points", samples.size()},
                     {"wood", sample_report.wood_points},
                     {"leaf", sample_report.leaf_points},
                     {"pulses", sample_report.pulses},
                     {"scanned_points", sample_report.scanned_points},
                     {"angular_step_deg", rounded(sample_report.angular_step_deg, 4)},
                     {"pulse_density", rounded(sample_report.pulse_density, 2)}}},
                   {"species",
                    {{"reconstruction", species.reconstruction.empty() ? json() : json(species.reconstruction)},
                     {"patches", profile.entry.name},
                     {"source", species.source},
                     {"probability", species.source == "classifier" ? json(rounded(species.probability, 4)) : json()}}},
                   {"reconstruction",
                    {{"internodes", reconstruction.summary.internodes},
                     {"height_m", rounded(reconstruction.summary.height, 3)},
                     {"used_points", reconstruction.summary.used_points},
                     {"branches", reconstruction.summary.branches}}},
                   {"lobes",
                    {{"count", tree.lobes.size()},
                     {"faces", lobe_faces},
                     {"main_nodes", tree.skeleton.size()},
                     {"points_in_lobes", lobe_report.lobe_points},
                     {"edges_measured_by_wood", lobe_report.wood_measured_edges}}},
                   {"sizes",
                    {{"original_bytes", original_bytes},
                     {"tlobe_bytes", tlobe_bytes.size()},
                     {"dbf6_bytes", dbf6_bytes},
                     {"budget_bytes", file_options.max_bytes},
                     {"within_budget", tlobe_bytes.size() <= file_options.max_bytes},
                     {"tlobe_lobe_faces", stored_lobe_faces},
                     {"tlobe_surfaces_from_occupancy", derived_surfaces},
                     {"tlobe_occupancy_cell_m", occupancy_cell},
                     {"compression_factor", rounded(original_bytes / static_cast<double>(tlobe_bytes.size()), 1)},
                     {"compression_factor_dbf6", dbf6_bytes > 0 ? json(rounded(original_bytes / dbf6_bytes, 1)) : json()}}},
                   {"rebuilt",
                    {{"triangles", rebuilt.triangles()},
                     {"wood_triangles", rebuilt.wood.faces.size()},
                     {"leaf_triangles", rebuilt.leaves.faces.size()},
                     {"leaves", rebuilt.leaf_count},
                     {"mesh_bytes", file_bytes(mesh_path)}}},
                   {"fidelity", fidelity},
                   {"outputs",
                    {{"tlobe", tlobe_path.string()},
                     {"dbf6", dbf6_path.string()},
                     {"mesh", mesh_path.string()},
                     {"skeleton", skeleton_path.string()},
                     {"samples", samples_path.string()},
                     {"comparison_png", png_path.string()},
                     {"crowns_png", crowns_path.string()},
                     {"report", report_path.string()}}},
                   {"seconds", seconds},
                   {"peak_memory_mb", rounded(peak_memory_mb(), 1)}};
    write_file_atomically(report_path, report.dump(2) + "\n");
    if (global.json)
        std::cout << report.dump(2) << "\n";
    else
        print_summary(report);
    return 0;
}

}  // namespace

void add_rebuild_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto o = std::make_shared<RebuildCliOptions>();
    // Livny et al. 2011 synthesized 0.5-3 M triangles per tree: the lower figure fills the lobes
    // of every bench species (at 200 000 the crowns of the 50 MB trees were half filled).
    o->synthesis.max_triangles = 500000;
    o->flags.species = "auto";
    CLI::App* sub = app.add_subcommand(
            "rebuild",
            "A heavy polygonal tree (OBJ/glb/PLY/OFF/STL) in, a light lobe-based tree (.tlobe, .dbf6) out, with a fidelity report");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("mesh", o->input, "Tree model: .obj or .glb (material/group names tell bark from leaves), .ply, .off, .stl")
            ->required();
    table->add("--out", o->out,
               "Output folder: <stem>.tlobe, .dbf6, _rebuilt.ply, _skeleton.ply, _samples.ply, _compare.png, _crowns.png, report.json")
            ->required();
    add_species_flags(*table, o->flags, "Lobe diameter factor f_s of Eq. 2 (default 1.0, or the species')", o->stage);
    sub->get_option("--species")
            ->description(
                    "Species from config/species.yaml, or auto: the classifier's choice with --model, else generic parameters and "
                    "lagerstroemia patches")
            ->capture_default_str();
    table->add("--model", o->model, "JointBoost model (`classify train`) that picks the species for --species auto");
    table->add("--scan", o->scan,
               "Sampling: uniform (area-weighted on the surface), tls (terrestrial scanner around the model), als (airborne)")
            ->check(CLI::IsMember({"uniform", "tls", "als"}));
    table->add("--samples", o->samples, "Points sampled (scans: at most, about this many)")->check(CLI::Range(100, 50000000));
    table->add("--density", o->density, "Uniform sampling: points per m^2 of surface instead of --samples")->check(PositiveNumber);
    table->add("--stations", o->stations, "TLS stations around the model")->check(CLI::Range(1, 16));
    table->add("--seed", o->seed, "Random seed of sampling and synthesis");
    table->add("--budget-kb", o->budget_kb,
               "Size the .tlobe may take (kB); its lobe surfaces are simplified, then its occupancy grid coarsened, to fit")
            ->check(CLI::Range(kMinBudgetBytes / 1000, 10000.0));
    table->add("--min-ratio", o->min_ratio,
               "Keep the .tlobe within the input mesh file's size / this where that is below --budget-kb (0: off)")
            ->check(CLI::Range(0.0, 1e6));
    table->add("--leaf-materials", o->leaf_materials,
               "Comma-separated names (substrings, any case) of leaf materials/groups/objects; other named faces are wood");
    table->add("--max-triangles", o->synthesis.max_triangles, "Triangles of the synthesized tree at most")
            ->check(CLI::Range(1000, 1000000000));
    table->add("--dbf6-resolution", o->dbf6_resolution, "DBF6 resolution r of the skeleton file")->check(PositiveNumber);
    table->add("--compare-samples", o->compare_samples, "Samples per surface for the distances original <-> rebuilt")
            ->check(CLI::Range(1000, 10000000));
    table->add("--image-height", o->image_height, "Height of the comparison PNG, pixels")->check(CLI::Range(64, 4096));
    sub->callback([o, table, &global, &job] { job = [o, table, &global] { return run_rebuild(*o, *table, global); }; });
}

}  // namespace treelobes::cli
