// segment_eval: runs the terrain and tree segmentation stages on one cloud and scores the result
// against per-point reference labels (synthetic truth or another tool's segmentation), for
// bench/segment_bench.sh and docs/segment.md.
//
//   segment_eval CLOUD [--mode auto|als|tls] [--stand broadleaf|conifer] [--reference ATTRIBUTE] [--min-height M]
//                [--ignore-classification] [--replicate N] [--trees] [--set name=value ...] [--dump FILE]
//
// Scores with score_segmentation (segment/segmentation_score.hpp: a reference tree and a found
// tree match when each holds at least half of the other's points; trees taller than
// --min-height, default 5 m, are counted). One JSON object on stdout.
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "segment/segment_trees.hpp"
#include "segment/segmentation_score.hpp"
#include "segment/terrain.hpp"

#include <nlohmann/json.hpp>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <vector>

using namespace treelobes;
using json = nlohmann::json;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double peak_memory_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

// N x N copies of the cloud side by side (throughput at larger sizes from one generated tile).
PointCloud replicate(const PointCloud& cloud, int n, std::vector<std::int32_t>& reference) {
    if (n <= 1) return cloud;
    const auto [low, high] = cloud.bounds();
    const Eigen::Vector3f step(high.x() - low.x() + 1.0f, high.y() - low.y() + 1.0f, 0.0f);
    PointCloud out;
    out.origin = cloud.origin;
    std::vector<std::int32_t> labels;
    std::int32_t largest = 0;
    for (auto r : reference) largest = std::max(largest, r);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::int32_t shift = (j * n + i) * (largest + 1);
            for (std::size_t p = 0; p < cloud.size(); ++p) {
                out.positions.push_back(cloud.positions[p] + Eigen::Vector3f(step.x() * i, step.y() * j, 0.0f));
                if (!cloud.classification.empty()) out.classification.push_back(cloud.classification[p]);
                if (!reference.empty()) labels.push_back(reference[p] ? reference[p] + shift : 0);
            }
        }
    reference.swap(labels);
    return out;
}

// Reference ids per point from an extra attribute; no-data, non-finite and non-positive are 0.
std::vector<std::int32_t> reference_labels(const PointCloud& cloud, const std::string& name) {
    std::vector<std::int32_t> labels(cloud.size(), 0);
    const ExtraAttribute* attribute = cloud.extra(name);
    if (!attribute) return labels;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const double v = attribute->values[i];
        const bool no_data = attribute->no_data && v == *attribute->no_data;
        if (std::isfinite(v) && !no_data && v > 0 && v < 2e9) labels[i] = static_cast<std::int32_t>(v);
    }
    return labels;
}

json score_json(const SegmentationScore& s) {
    json table = json::array();
    for (const auto& row : s.by_height)
        table.push_back({{"height", row.name}, {"reference", row.reference}, {"found", row.found}, {"matched", row.matched}});
    return {{"reference_trees", s.reference_trees},
            {"found_trees", s.found_trees},
            {"matched", s.matched},
            {"precision", s.precision},
            {"recall", s.recall},
            {"f1", s.f1},
            {"points_right", s.points_right},
            {"by_height", table}};
}

// --set name=value for the airborne and terrestrial parameters the bench sweeps.
void set_option(SegmentOptions& o, const std::string& assignment) {
    const auto equals = assignment.find('=');
    if (equals == std::string::npos) throw Error::usage("--set needs name=value");
    const std::string name = assignment.substr(0, equals);
    const float v = std::stof(assignment.substr(equals + 1));
    const std::map<std::string, float*> fields = {{"chm_cell", &o.chm_cell},
                                                  {"point_radius", &o.point_radius},
                                                  {"cell_per_spacing", &o.cell_per_spacing},
                                                  {"disc_per_spacing", &o.disc_per_spacing},
                                                  {"sparse_disc_per_spacing", &o.sparse_disc_per_spacing},
                                                  {"pit_depth", &o.pit_depth},
                                                  {"window_base", &o.window_base},
                                                  {"window_per_metre", &o.window_per_metre},
                                                  {"max_window", &o.max_window},
                                                  {"min_top_prominence", &o.min_top_prominence},
                                                  {"top_prominence_ratio", &o.top_prominence_ratio},
                                                  {"merge_pass_ratio", &o.merge_pass_ratio},
                                                  {"chm_smoothing", &o.chm_smoothing},
                                                  {"max_stem_lean", &o.max_stem_lean},
                                                  {"min_quarter_arc_share", &o.min_quarter_arc_share},
                                                  {"stem_layer_height", &o.stem_layer_height},
                                                  {"trunk_layer_height", &o.trunk_layer_height},
                                                  {"graph_beta", &o.graph_beta},
                                                  {"stem_reach_exponent", &o.stem_reach_exponent},
                                                  {"stem_subcluster_distance", &o.stem_subcluster_distance},
                                                  {"stem_merge_distance", &o.stem_merge_distance},
                                                  {"shared_top_stem_distance", &o.shared_top_stem_distance},
                                                  {"shared_top_distance", &o.shared_top_distance},
                                                  {"seed_ratio", &o.seed_ratio},
                                                  {"crown_ratio", &o.crown_ratio},
                                                  {"max_crown_radius", &o.max_crown_radius},
                                                  {"min_tree_height", &o.min_tree_height},
                                                  {"max_gap", &o.max_gap},
                                                  {"attach_gap", &o.attach_gap},
                                                  {"detached_min_height", &o.detached_min_height},
                                                  {"graph_voxel", &o.graph_voxel},
                                                  {"stem_slice_low", &o.stem_slice_low},
                                                  {"stem_slice_high", &o.stem_slice_high},
                                                  {"min_circle_inliers", &o.min_circle_inliers},
                                                  {"max_stem_radius", &o.max_stem_radius},
                                                  {"stem_foot_reach", &o.stem_foot_reach},
                                                  {"buttressed_stem_radius", &o.buttressed_stem_radius},
                                                  {"buttressed_foot_reach", &o.buttressed_foot_reach},
                                                  {"min_arc_coverage", &o.min_arc_coverage},
                                                  {"circle_tolerance", &o.circle_tolerance},
                                                  {"ground_clearance", &o.ground_clearance}};
    const std::map<std::string, int*> counts = {{"graph_neighbours", &o.graph_neighbours},
                                                {"min_stem_points", &o.min_stem_points},
                                                {"min_detached_voxels", &o.min_detached_voxels}};
    if (const auto count = counts.find(name); count != counts.end()) {
        *count->second = static_cast<int>(v);
        return;
    }
    const auto field = fields.find(name);
    if (field == fields.end()) throw Error::usage("--set: unknown option " + name);
    *field->second = v;
}

int run(int argc, char** argv) {
    if (argc < 2)
        throw Error::usage(
                "usage: segment_eval CLOUD [--mode auto|als|tls] [--stand broadleaf|conifer] [--reference ATTRIBUTE] [--min-height M] "
                "[--ignore-classification] [--replicate N] [--trees] [--set name=value] [--dump FILE]");
    const std::string path = argv[1];
    SegmentOptions segment_options;
    TerrainOptions terrain_options;
    std::string reference_name;
    float min_height = 5.0f;
    int copies = 1;
    bool list_trees = false;
    std::string dump_path;
    for (int a = 2; a < argc; ++a) {
        const std::string flag = argv[a];
        const auto value = [&]() -> std::string {
            if (a + 1 >= argc) throw Error::usage(flag + " needs a value");
            return argv[++a];
        };
        if (flag == "--mode")
            segment_options.mode = parse_scan_mode(value());
        else if (flag == "--stand")
            segment_options = with_stand_type(segment_options, parse_stand_type(value()));
        else if (flag == "--reference")
            reference_name = value();
        else if (flag == "--min-height")
            min_height = std::stof(value());
        else if (flag == "--ignore-classification")
            terrain_options.use_classification = false;
        else if (flag == "--replicate")
            copies = std::stoi(value());
        else if (flag == "--trees")
            list_trees = true;
        else if (flag == "--set")
            set_option(segment_options, value());
        else if (flag == "--dump")
            dump_path = value();
        else
            throw Error::usage("unknown flag " + flag);
    }
    const PointCloud input = read_point_cloud(path);
    std::vector<std::int32_t> reference = reference_name.empty() ? std::vector<std::int32_t>{} : reference_labels(input, reference_name);
    const PointCloud cloud = replicate(input, copies, reference);
    const double memory_before = peak_memory_mb();

    const auto start = std::chrono::steady_clock::now();
    const Terrain terrain = analyse_terrain(cloud, terrain_options);
    const double terrain_seconds = seconds_since(start);
    const TreeSegmentation trees = segment_trees(cloud, terrain, segment_options);
    const double total_seconds = seconds_since(start);

    json out = {{"cloud", path},
                {"points", cloud.size()},
                {"ground_source", terrain.ground_source},
                {"ground_points", terrain.ground_points},
                {"mode", scan_mode_name(trees.mode_used)},
                {"mode_reason", trees.mode_reason},
                {"chm",
                 {{"return_spacing", trees.return_spacing},
                  {"pulse_density", trees.pulse_density},
                  {"cell", trees.chm_cell},
                  {"point_radius", trees.chm_point_radius}}},
                {"trees", trees.trees.size()},
                {"seconds", {{"terrain", terrain_seconds}, {"segment", total_seconds - terrain_seconds}, {"total", total_seconds}}},
                {"peak_memory_mb", peak_memory_mb()},
                {"peak_memory_mb_after_reading", memory_before}};
    if (std::count(cloud.classification.begin(), cloud.classification.end(), std::uint8_t{2}) > 0) {
        // The input's ground class as a check of the terrain (meaningful with
        // --ignore-classification): share of its points found as ground, RMS of their height above the DTM.
        std::size_t count = 0, found = 0;
        double squares = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (cloud.classification[i] != 2) continue;
            ++count;
            found += terrain.is_ground[i];
            squares += static_cast<double>(terrain.height_above_ground[i]) * terrain.height_above_ground[i];
        }
        out["ground_check"] = {{"class2_points", count},
                               {"found_as_ground", static_cast<double>(found) / count},
                               {"rms_height_m", std::sqrt(squares / count)}};
    }
    if (!reference.empty())
        out["score"] = score_json(score_segmentation(reference, trees.tree_id, terrain.height_above_ground, min_height));
    if (list_trees) {
        // Heights as `treelobes tile` measures them (docs/tile.md, height_m): the tree's highest
        // point above the ground at its base, not the largest height above the terrain under its
        // points, which on a slope is another point when the crown reaches downhill.
        std::vector<float> highest(trees.trees.size() + 1, -std::numeric_limits<float>::infinity());
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            float& z = highest[static_cast<std::size_t>(trees.tree_id[i])];
            z = std::max(z, cloud.positions[i].z());
        }
        json list = json::array();
        for (const auto& t : trees.trees)
            list.push_back({{"id", t.id},
                            {"x", t.base.x()},
                            {"y", t.base.y()},
                            {"height", highest[static_cast<std::size_t>(t.id)] - t.base.z()},
                            {"stem_radius", t.stem_radius},
                            {"points", t.points}});
        out["tree_list"] = list;
    }
    if (!dump_path.empty()) {
        // Per-point table for inspecting disagreements: x y z height_above_ground reference found.
        std::ofstream dump(dump_path);
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const Eigen::Vector3f& p = cloud.positions[i];
            dump << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << terrain.height_above_ground[i] << ' '
                 << (reference.empty() ? 0 : reference[i]) << ' ' << trees.tree_id[i] << '\n';
        }
    }
    std::cout << out.dump() << "\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const Error& e) {
        std::cerr << "segment_eval: " << e.what() << "\n";
        return static_cast<int>(e.code());
    } catch (const std::exception& e) {
        std::cerr << "segment_eval: " << e.what() << "\n";
        return 1;
    }
}
