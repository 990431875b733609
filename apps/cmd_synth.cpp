// `treelobes synth tree|dataset|tile`: synthetic trees with ground truth and simulated scans.
//   tree     one tree: scan (LAS), true skeleton (PLY), mesh (PLY), truth JSON, optional PNGs
//   dataset  K trees per species: <species>/<name>.las + _skeleton.ply + _truth.json, labels.csv
//   tile     a forest tile: tile.las (treeID/species/wood/internode extra bytes), truth.csv,
//            skeletons/tree_<id>.ply
// Every run is determined by --seed; summary.json records options, counts, timings and memory.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/summary_values.hpp"
#include "config/species_profile.hpp"
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "core/version.hpp"
#include "render/rasterizer.hpp"
#include "synth/scanner.hpp"
#include "synth/tile.hpp"
#include "synth/tree_mesh.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

namespace fs = std::filesystem;

namespace treelobes::cli {

namespace {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

// Flags shared by the three subcommands. Beam flags are optional so each scanner keeps its own
// defaults unless the user sets them.
struct SynthFlags {
    std::string species_file;
    std::string out;
    std::uint64_t seed = 1;
    std::string scanner;
    std::string cloud_format = "las";
    synth::TlsOptions tls;
    synth::AlsOptions als;
    std::optional<double> divergence, noise, separation, threshold;
    std::optional<int> sub_rays, max_returns;
    synth::GrowOptions grow;
    bool no_leaves = false;
    double outliers = 0;
    bool overwrite = false;
    bool preview = false;
    int preview_height = 800;
};

struct TreeFlags {
    std::string species;
    double height = 0;
    double ground_margin = 2.0;
    bool no_mesh = false;
    std::string mesh_format = "ply";
};

struct DatasetFlags {
    int per_species = 5;
    std::vector<std::string> species;
    bool mesh = false;
};

struct TileFlags {
    synth::TileOptions tile;
    std::vector<double> origin;
    double station_spacing = 20;
};

void add_scan_flags(OptionTable& table, SynthFlags& f) {
    table.add("--scanner", f.scanner, "tls (terrestrial) or als (airborne)")->check(CLI::IsMember({"tls", "als"}));
    table.add("--stations", f.tls.stations, "TLS stations around the scene (1-16)");
    table.add("--station-distance", f.tls.station_distance_m, "TLS distance of the stations from the trees, m (0 = auto)");
    table.add("--angular-step", f.tls.angular_step_deg, "TLS angular step, degrees");
    table.add("--max-range", f.tls.max_range_m, "TLS maximum range, m");
    table.add("--pulse-density", f.als.pulse_density, "ALS pulses per m^2 (one strip)");
    table.add("--altitude", f.als.altitude_m, "ALS flying height above the ground, m");
    table.add("--scan-angle", f.als.max_scan_angle_deg, "ALS maximum scan angle, +- degrees");
    table.add("--strip-overlap", f.als.strip_overlap, "ALS overlap of neighbouring strips (0-0.9)");
    table.add("--divergence", f.divergence, "Beam divergence, mrad (TLS 0.3, ALS 0.5)");
    table.add("--sub-rays", f.sub_rays, "Rays per pulse across the beam: 1, 7, 19 or 37 (TLS 1, ALS 19)");
    table.add("--noise", f.noise, "Gaussian range noise sigma, m (TLS 0.005, ALS 0.03)");
    table.add("--max-returns", f.max_returns, "Returns recorded per pulse (TLS 1, ALS 5)");
    table.add("--return-separation", f.separation, "Minimum distance between returns, m (TLS 0.5, ALS 1.5)");
    table.add("--detection-threshold", f.threshold, "Energy a return needs, fraction of the pulse (TLS 0.02, ALS 0.05)");
    table.add("--outliers", f.outliers, "Fraction of scattered noise points added (class 7)");
}

void add_common_flags(OptionTable& table, SynthFlags& f) {
    table.add("--out", f.out, "Output folder (created if missing)")->required();
    table.add("--seed", f.seed, "Random seed: the same seed gives byte-identical files");
    table.add("--species-file", f.species_file, "Species library (default: config/species.yaml or $TREELOBES_SPECIES)");
    table.add("--cloud-format", f.cloud_format, "Scan file format: las or ply")->check(CLI::IsMember({"las", "ply"}));
    table.add("--leaf-density", f.grow.leaf_density, "Leaves x this, each 1/sqrt(this) larger: same leaf area (0.001-4)");
    table.add("--max-leaves", f.grow.max_leaves, "Leaf budget per tree; beyond it leaves get fewer and larger");
    table.add_flag("--no-leaves", f.no_leaves, "Leafless trees");
    table.add_flag("--overwrite", f.overwrite, "Replace existing outputs (default: keep finished ones)");
    add_scan_flags(table, f);
}

// Resolves the beam flags onto the chosen scanner's options.
void apply_beam(SynthFlags& f) {
    synth::BeamOptions& beam = f.scanner == "als" ? f.als.beam : f.tls.beam;
    if (f.divergence) beam.divergence_mrad = *f.divergence;
    if (f.sub_rays) beam.sub_rays = *f.sub_rays;
    if (f.noise) beam.range_noise_m = *f.noise;
    if (f.max_returns) beam.max_returns = *f.max_returns;
    if (f.separation) beam.min_separation_m = *f.separation;
    if (f.threshold) beam.detection_threshold = *f.threshold;
    f.grow.leaves = !f.no_leaves;
    if (f.scanner == "als")
        synth::check_options(f.als);
    else
        synth::check_options(f.tls);
}

json beam_json(const synth::BeamOptions& b) {
    return {{"divergence_mrad", b.divergence_mrad},   {"sub_rays", b.sub_rays},
            {"range_noise_m", b.range_noise_m},       {"max_returns", b.max_returns},
            {"min_separation_m", b.min_separation_m}, {"detection_threshold", b.detection_threshold}};
}

json scanner_json(const SynthFlags& f) {
    if (f.scanner == "als")
        return {{"type", "als"},
                {"altitude_m", f.als.altitude_m},
                {"pulse_density", f.als.pulse_density},
                {"max_scan_angle_deg", f.als.max_scan_angle_deg},
                {"strip_overlap", f.als.strip_overlap},
                {"beam", beam_json(f.als.beam)},
                {"outliers", f.outliers}};
    return {{"type", "tls"},
            {"stations", f.tls.station_xy.empty() ? f.tls.stations : static_cast<int>(f.tls.station_xy.size())},
            {"station_distance_m", f.tls.station_distance_m},
            {"angular_step_deg", f.tls.angular_step_deg},
            {"max_range_m", f.tls.max_range_m},
            {"beam", beam_json(f.tls.beam)},
            {"outliers", f.outliers}};
}

PointCloud run_scan(const synth::Scene& scene, const SynthFlags& f, std::uint64_t seed, synth::ScanSummary& summary) {
    PointCloud cloud = f.scanner == "als" ? synth::scan_als(scene, f.als, seed, &summary) : synth::scan_tls(scene, f.tls, seed, &summary);
    if (f.outliers > 0) {
        const auto [lo, hi] = scene.bounds();
        synth::add_outliers(cloud, lo, hi, f.outliers, seed);
    }
    return cloud;
}

std::vector<SpeciesProfile> load_library(const SynthFlags& f) {
    return load_species_profiles(f.species_file.empty() ? default_species_file() : fs::path(f.species_file));
}

fs::path prepare_folder(const std::string& out) {
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec || !fs::is_directory(out)) throw Error::input(out, "cannot create the output folder");
    return out;
}

json metrics_json(const synth::TreeMetrics& m, double age) {
    return {{"height_m", m.height_m},
            {"dbh_m", m.dbh_m},
            {"crown_diameter_m", m.crown_diameter_m},
            {"age_years", age},
            {"internodes", m.internodes},
            {"leaves", m.leaves},
            {"leaf_area_m2", m.leaf_area_m2},
            {"lai", m.lai},
            {"skeleton_length_m", m.total_length_m}};
}

// The two panels next to each other on a white background.
render::Image side_by_side(const render::Image& left, const render::Image& right) {
    render::Image both(left.width + right.width, std::max(left.height, right.height), {255, 255, 255, 255});
    for (int y = 0; y < left.height; ++y)
        for (int x = 0; x < left.width; ++x) both.set(x, y, left.at(x, y));
    for (int y = 0; y < right.height; ++y)
        for (int x = 0; x < right.width; ++x) both.set(left.width + x, y, right.at(x, y));
    return both;
}

// Side-view PNGs: the mesh (bark brown, leaves green) and the scan (wood brown, leaves green,
// ground grey), framed alike so they can be compared, and both side by side (docs/species/).
void write_previews(const synth::TreeMesh& mesh, const PointCloud& cloud, const fs::path& stem, int height) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const auto& v : mesh.wood.vertices) lo = lo.cwiseMin(v.cast<double>()), hi = hi.cwiseMax(v.cast<double>());
    for (const auto& v : mesh.leaves.vertices) lo = lo.cwiseMin(v.cast<double>()), hi = hi.cwiseMax(v.cast<double>());
    if (!(lo.x() <= hi.x())) return;
    const render::View view = render::View::side(lo, hi, 0.0, 10.0);
    const int width =
            std::max(200, static_cast<int>(height * std::max(hi.x() - lo.x(), hi.y() - lo.y()) / std::max(1e-6, hi.z() - lo.z())));
    render::Rasterizer tree(width, height, view);
    tree.draw_mesh(mesh.wood, {110, 75, 45, 255});
    tree.draw_mesh(mesh.leaves, {70, 140, 50, 255});
    render::write_png(tree.image(), stem.string() + "_mesh.png");

    render::Rasterizer scan(width, height, view);
    std::vector<Eigen::Vector3d> points;
    std::vector<render::Rgba> colours;
    const ExtraAttribute* wood = cloud.extra("wood");
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud.global(i);
        if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) continue;
        points.push_back(p);
        const bool ground = !cloud.classification.empty() && cloud.classification[i] == 2;
        colours.push_back(ground ? render::Rgba{150, 150, 150, 255}
                                 : (wood && wood->values[i] > 0.5 ? render::Rgba{120, 70, 30, 255} : render::Rgba{60, 150, 60, 255}));
    }
    scan.draw_points(points, colours, 1);
    render::write_png(scan.image(), stem.string() + "_scan.png");
    render::write_png(side_by_side(tree.image(), scan.image()), stem.string() + "_preview.png");
}

struct TreeResult {
    json truth;
    std::size_t points = 0;
};

// Grows, scans and writes one tree as <folder>/<name>.* ; returns its truth record.
TreeResult make_tree(const SpeciesProfile& profile, std::uint64_t seed, const SynthFlags& f, const TreeFlags& t, bool mesh,
                     const fs::path& folder, const std::string& name) {
    synth::GrowOptions grow = f.grow;
    if (t.height > 0) grow.height_m = t.height;
    synth::SyntheticTree tree = synth::grow(profile, seed, grow);
    const synth::TreeMetrics metrics = synth::measure(tree);
    const double age = tree.age_years;
    const fs::path stem = folder / name;
    write_skeleton_ply(tree.skeleton, stem.string() + "_skeleton.ply");
    std::optional<synth::TreeMesh> tree_mesh;
    if (mesh || f.preview) tree_mesh = synth::tree_mesh(tree);
    if (mesh) write_named_mesh(tree_mesh->named(), stem.string() + "_mesh." + t.mesh_format);

    const synth::Scene scene = synth::single_tree_scene(std::move(tree), t.ground_margin, seed);
    synth::ScanSummary scan;
    const PointCloud cloud = run_scan(scene, f, seed, scan);
    write_point_cloud(cloud, stem.string() + "." + f.cloud_format);
    if (f.preview) write_previews(*tree_mesh, cloud, stem, f.preview_height);

    TreeResult result;
    result.points = cloud.size();
    result.truth = {{"name", name},
                    {"species", profile.entry.name},
                    {"species_id", profile.entry.id},
                    {"seed", seed},
                    {"tree", metrics_json(metrics, age)},
                    {"scan", {{"pulses", scan.pulses}, {"rays", scan.rays}, {"points", cloud.size()}}}};
    write_file_atomically(stem.string() + "_truth.json", result.truth.dump(2) + "\n");
    return result;
}

void print_or_json(const json& summary, const GlobalOptions& global, const std::string& human) {
    if (global.json)
        std::cout << summary.dump(2) << "\n";
    else
        std::cout << human;
}

int run_tree(SynthFlags f, const TreeFlags& t, const OptionTable& table, const GlobalOptions& global) {
    const auto start = Clock::now();
    if (f.scanner.empty()) f.scanner = "tls";
    apply_beam(f);
    const auto library = load_library(f);
    const SpeciesProfile& profile = find_species_profile(library, t.species);
    const fs::path folder = prepare_folder(f.out);
    const std::string name = profile.entry.name + "_" + std::to_string(f.seed);
    const TreeResult r = make_tree(profile, f.seed, f, t, !t.no_mesh, folder, name);

    json summary = r.truth;
    summary["treelobes"] = kVersion;
    summary["options"] = table.json();
    summary["scanner"] = scanner_json(f);
    summary["outputs"] = json::array();
    for (const std::string& suffix : {"." + f.cloud_format, std::string("_skeleton.ply"), std::string("_truth.json")})
        summary["outputs"].push_back((folder / (name + suffix)).string());
    if (!t.no_mesh) summary["outputs"].push_back((folder / (name + "_mesh." + t.mesh_format)).string());
    if (f.preview) {
        summary["outputs"].push_back((folder / (name + "_mesh.png")).string());
        summary["outputs"].push_back((folder / (name + "_scan.png")).string());
        summary["outputs"].push_back((folder / (name + "_preview.png")).string());
    }
    summary["seconds"] = seconds_since(start);
    summary["peak_memory_mb"] = peak_memory_mb();
    const json& tree = r.truth["tree"];
    print_or_json(
            summary, global,
            profile.entry.display_name + " (seed " + std::to_string(f.seed) + "): " +
                    format_numbers("height %.1f m, DBH %.2f m, crown %.1f m", tree["height_m"], tree["dbh_m"], tree["crown_diameter_m"]) +
                    ", " + std::to_string(tree["internodes"].get<std::size_t>()) + " internodes, " +
                    std::to_string(tree["leaves"].get<std::size_t>()) + " leaves\n" + f.scanner + " scan: " + std::to_string(r.points) +
                    " points -> " + (folder / (name + "." + f.cloud_format)).string() + format_numbers(" (%.1f s)\n", summary["seconds"]));
    return 0;
}

std::string labels_header() { return "file,species,species_id,seed,height_m,dbh_m,crown_diameter_m,age_years,points\n"; }

std::string labels_row(const std::string& file, const json& truth) {
    const json& tree = truth["tree"];
    char line[512];
    std::snprintf(line, sizeof line, "%s,%s,%d,%llu,%.2f,%.3f,%.2f,%.0f,%zu\n", file.c_str(), truth["species"].get<std::string>().c_str(),
                  truth["species_id"].get<int>(), static_cast<unsigned long long>(truth["seed"].get<std::uint64_t>()),
                  tree["height_m"].get<double>(), tree["dbh_m"].get<double>(), tree["crown_diameter_m"].get<double>(),
                  tree["age_years"].get<double>(), truth["scan"]["points"].get<std::size_t>());
    return line;
}

int run_dataset(SynthFlags f, const DatasetFlags& d, const OptionTable& table, const GlobalOptions& global) {
    const auto start = Clock::now();
    if (f.scanner.empty()) f.scanner = "tls";
    apply_beam(f);
    if (d.per_species < 1 || d.per_species > 100000) throw Error::usage("--per-species must be in [1, 100000]");
    const auto library = load_library(f);
    std::vector<const SpeciesProfile*> chosen;
    for (const auto& name : d.species) chosen.push_back(&find_species_profile(library, name));
    if (d.species.empty())
        for (const auto& p : library) chosen.push_back(&p);
    const fs::path folder = prepare_folder(f.out);

    std::string labels = labels_header();
    std::string failures;
    std::size_t made = 0, skipped = 0, failed = 0, points = 0;
    Progress progress("synth dataset", chosen.size() * static_cast<std::size_t>(d.per_species));
    for (const SpeciesProfile* profile : chosen) {
        const fs::path sub = prepare_folder((folder / profile->entry.name).string());
        for (int k = 0; k < d.per_species; ++k) {
            const std::uint64_t seed = synth::tree_seed(f.seed, static_cast<std::uint64_t>(profile->entry.id) * 1000000ULL + k);
            const std::string name = profile->entry.name + "_" + std::to_string(k);
            const std::string file = profile->entry.name + "/" + name + "." + f.cloud_format;
            const fs::path truth_file = sub / (name + "_truth.json");
            try {
                json truth;
                if (!f.overwrite && fs::exists(folder / file) && fs::exists(truth_file)) {
                    truth = json::parse(read_file(truth_file));  // resume: finished trees are kept
                    ++skipped;
                } else {
                    truth = make_tree(*profile, seed, f, TreeFlags{}, d.mesh, sub, name).truth;
                    ++made;
                }
                points += truth["scan"]["points"].get<std::size_t>();
                labels += labels_row(file, truth);
            } catch (const Error& e) {
                ++failed;
                failures += json{{"item", file}, {"seed", seed}, {"reason", e.what()}}.dump() + "\n";
                log_warn(file + ": " + e.what());
            } catch (const json::exception& e) {
                ++failed;
                failures +=
                        json{{"item", file}, {"seed", seed}, {"reason", std::string("unreadable truth file: ") + e.what()}}.dump() + "\n";
            }
            progress.advance();
        }
    }
    progress.finish();
    write_file_atomically(folder / "labels.csv", labels);
    if (failed) write_file_atomically(folder / "failures.jsonl", failures);

    json summary = {{"treelobes", kVersion},
                    {"command", "synth dataset"},
                    {"options", table.json()},
                    {"seed", f.seed},
                    {"per_species", d.per_species},
                    {"species", json::array()},
                    {"scanner", scanner_json(f)},
                    {"leaf_density", f.grow.leaf_density},
                    {"max_leaves", f.grow.max_leaves},
                    {"trees", {{"made", made}, {"kept", skipped}, {"failed", failed}}},
                    {"points", points},
                    {"labels", (folder / "labels.csv").string()},
                    {"seconds", seconds_since(start)},
                    {"peak_memory_mb", peak_memory_mb()}};
    for (const auto* p : chosen) summary["species"].push_back(p->entry.name);
    write_file_atomically(folder / "summary.json", summary.dump(2) + "\n");
    print_or_json(summary, global,
                  std::to_string(made + skipped) + " trees of " + std::to_string(chosen.size()) + " species (" + std::to_string(made) +
                          " made, " + std::to_string(skipped) + " kept, " + std::to_string(failed) + " failed), " + std::to_string(points) +
                          " points -> " + (folder / "labels.csv").string() + format_numbers(" (%.1f s)\n", summary["seconds"]));
    return failed ? static_cast<int>(ExitCode::PartialFailure) : 0;
}

// TLS over a tile: stations on a square grid.
std::vector<Eigen::Vector2d> station_grid(double size, double spacing) {
    std::vector<Eigen::Vector2d> stations;
    const int n = std::max(1, static_cast<int>(std::floor(size / spacing)));
    const double step = size / n;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) stations.emplace_back((i + 0.5) * step, (j + 0.5) * step);
    return stations;
}

int run_tile(SynthFlags f, TileFlags t, const OptionTable& table, const GlobalOptions& global) {
    const auto start = Clock::now();
    if (f.scanner.empty()) f.scanner = "als";
    apply_beam(f);
    if (!t.origin.empty()) {
        if (t.origin.size() != 3) throw Error::usage("--origin needs three numbers: X Y Z");
        t.tile.origin = Eigen::Vector3d(t.origin[0], t.origin[1], t.origin[2]);
    }
    if (f.scanner == "tls") {
        if (!(t.station_spacing >= 2)) throw Error::usage("--station-spacing must be at least 2 m");
        f.tls.station_xy = station_grid(t.tile.size_m, t.station_spacing);
    }
    t.tile.grow = f.grow;
    const auto library = load_library(f);
    const fs::path folder = prepare_folder(f.out);
    const fs::path cloud_file = folder / ("tile." + f.cloud_format);

    log_info("synth tile: growing " + std::to_string(t.tile.trees) + " trees");
    const synth::Tile tile = synth::make_tile(library, f.seed, t.tile);
    const double grow_seconds = seconds_since(start);
    log_info("synth tile: scanning");
    synth::ScanSummary scan;
    PointCloud cloud = run_scan(tile.scene, f, f.seed, scan);
    const double scan_seconds = seconds_since(start) - grow_seconds;
    write_point_cloud(cloud, cloud_file);
    write_file_atomically(folder / "truth.csv", synth::truth_csv(tile.truth));
    const fs::path skeletons = prepare_folder((folder / "skeletons").string());
    Progress progress("synth tile skeletons", tile.scene.trees.size());
    for (const auto& placed : tile.scene.trees) {
        // Skeletons in the tile frame, like the scan.
        TreeGraph skeleton = placed.tree.skeleton;
        for (auto& node : skeleton.nodes) node.position += placed.position.cast<float>();
        skeleton.origin = tile.scene.origin;
        write_skeleton_ply(skeleton, skeletons / ("tree_" + std::to_string(placed.tree_id) + ".ply"));
        progress.advance();
    }
    progress.finish();

    std::size_t ground = 0;
    for (auto c : cloud.classification) ground += c == 2;
    const double area = t.tile.size_m * t.tile.size_m;
    json summary = {{"treelobes", kVersion},
                    {"command", "synth tile"},
                    {"options", table.json()},
                    {"seed", f.seed},
                    {"tile",
                     {{"size_m", t.tile.size_m},
                      {"trees", tile.scene.trees.size()},
                      {"slope_deg", t.tile.slope_deg},
                      {"competition", t.tile.competition},
                      {"understory_per_100m2", t.tile.understory_per_100m2},
                      {"understory_blades", tile.scene.understory.size()}}},
                    {"scanner", scanner_json(f)},
                    {"leaf_density", f.grow.leaf_density},
                    {"max_leaves", f.grow.max_leaves},
                    {"pulses", scan.pulses},
                    {"points", cloud.size()},
                    {"points_per_m2", cloud.size() / area},
                    {"ground_fraction", cloud.empty() ? 0.0 : static_cast<double>(ground) / cloud.size()},
                    {"outputs", {cloud_file.string(), (folder / "truth.csv").string(), skeletons.string()}},
                    {"seconds", {{"grow", grow_seconds}, {"scan", scan_seconds}, {"total", seconds_since(start)}}},
                    {"peak_memory_mb", peak_memory_mb()}};
    write_file_atomically(folder / "summary.json", summary.dump(2) + "\n");
    print_or_json(summary, global,
                  format_numbers("tile %.0f x %.0f m", t.tile.size_m, t.tile.size_m) + ", " + std::to_string(tile.scene.trees.size()) +
                          " trees, " + f.scanner + " scan: " + std::to_string(cloud.size()) +
                          format_numbers(" points (%.2f per m^2) -> ", cloud.size() / area) + cloud_file.string() +
                          format_numbers(" (%.1f s)\n", seconds_since(start)));
    return 0;
}

}  // namespace

void add_synth_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    CLI::App* synth = app.add_subcommand("synth", "Synthetic trees with ground truth and simulated TLS/ALS scans");
    synth->require_subcommand(1);

    auto tree_flags = std::make_shared<SynthFlags>();
    auto tree = std::make_shared<TreeFlags>();
    CLI::App* tree_cmd = synth->add_subcommand("tree", "One tree: scan, true skeleton, mesh and truth");
    auto tree_table = std::make_shared<OptionTable>(tree_cmd);
    tree_table->add("--species", tree->species, "Species name (see config/species.yaml)")->required();
    tree_table->add("--height", tree->height, "Tree height, m (default: drawn from the species' range)");
    tree_table->add("--ground-margin", tree->ground_margin, "Ground scanned beyond the crown, m");
    tree_table->add_flag("--no-mesh", tree->no_mesh, "Do not write the tree mesh");
    tree_table
            ->add("--mesh-format", tree->mesh_format, "Tree mesh file: ply (geometry) or obj (objects, groups and materials: bark / leaf)")
            ->check(CLI::IsMember({"ply", "obj"}));
    tree_table->add_flag("--preview", tree_flags->preview,
                         "Also write <name>_mesh.png, <name>_scan.png and both side by side, <name>_preview.png");
    tree_table->add("--preview-height", tree_flags->preview_height, "Height of the preview PNGs, pixels")->check(CLI::Range(64, 4096));
    add_common_flags(*tree_table, *tree_flags);
    tree_cmd->callback([tree_flags, tree, tree_table, &global, &job] {
        job = [tree_flags, tree, tree_table, &global] { return run_tree(*tree_flags, *tree, *tree_table, global); };
    });

    auto data_flags = std::make_shared<SynthFlags>();
    auto data = std::make_shared<DatasetFlags>();
    // Hundreds of trees: a coarser raster and leaf budget than `synth tree` keep files and time small.
    data_flags->tls.angular_step_deg = 0.25;
    data_flags->grow.max_leaves = 100000;
    CLI::App* data_cmd = synth->add_subcommand("dataset", "K scanned trees per species with labels.csv");
    auto data_table = std::make_shared<OptionTable>(data_cmd);
    data_table->add("--per-species", data->per_species, "Trees per species");
    data_table->add("--species", data->species, "Species to include (default: all)");
    data_table->add_flag("--mesh", data->mesh, "Also write tree meshes");
    add_common_flags(*data_table, *data_flags);
    data_cmd->callback([data_flags, data, data_table, &global, &job] {
        job = [data_flags, data, data_table, &global] { return run_dataset(*data_flags, *data, *data_table, global); };
    });

    auto tile_flags = std::make_shared<SynthFlags>();
    auto tile = std::make_shared<TileFlags>();
    tile_flags->grow.max_leaves = 20000;  // hundreds of trees must fit in memory; leaf area is kept
    tile_flags->outliers = 0.0005;
    CLI::App* tile_cmd = synth->add_subcommand("tile", "A forest tile: LAS 1.4 with tree labels, truth.csv, skeletons");
    auto tile_table = std::make_shared<OptionTable>(tile_cmd);
    tile_table->add("--trees", tile->tile.trees, "Number of trees");
    tile_table->add("--size", tile->tile.size_m, "Tile side, m");
    tile_table->add("--species", tile->tile.species, "Species to mix (default: all)");
    tile_table->add("--slope", tile->tile.slope_deg, "Terrain slope, degrees");
    tile_table->add("--roughness", tile->tile.roughness_m, "Terrain roughness amplitude, m");
    tile_table->add("--understory", tile->tile.understory_per_100m2, "Bushes per 100 m^2 (0 = none)");
    tile_table->add("--spacing", tile->tile.spacing, "Minimum stem distance as a fraction of the summed crown radii");
    tile_table->add_flag("--competition", tile->tile.competition,
                         "Neighbours compete for crown space: branches growing where a neighbour owns the canopy are cut "
                         "(without it, crowded crowns interpenetrate)");
    tile_table->add("--origin", tile->origin, "Coordinates of the tile corner: X Y Z")->expected(3);
    tile_table->add("--station-spacing", tile->station_spacing,
                    "TLS: distance between stations on the grid, m (a station on a trunk moves clear of it)");
    add_common_flags(*tile_table, *tile_flags);
    tile_cmd->callback([tile_flags, tile, tile_table, &global, &job] {
        job = [tile_flags, tile, tile_table, &global] { return run_tile(*tile_flags, *tile, *tile_table, global); };
    });
}

}  // namespace treelobes::cli
