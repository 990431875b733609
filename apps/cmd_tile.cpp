// `treelobes tile INPUT --out DIR`: a LiDAR tile in, every tree out. Terrain (ground, DTM,
// height above ground) and tree segmentation (segment/), then every tree through the per-tree
// pipeline (forestry/tree_pipeline.hpp: skeleton, lobes, DBF6, measures, species) in its own
// error boundary, then the tile's tables, points, forest file and pictures (docs/tile.md).
// Finished outputs are kept on a re-run unless --overwrite (trees whose record and files exist
// are read back instead of made again). With --buffer the neighbouring tiles' points within the
// buffer are read too, and the tile keeps the trees whose stem base lies in its core
// (survey/buffered_tile.hpp); every tree gets a survey-wide id from its base (survey/tree_id.hpp).
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/summary_values.hpp"
#include "classify/jointboost.hpp"
#include "core/asprs_classes.hpp"
#include "core/atomic_file.hpp"
#include "core/cloud_header.hpp"
#include "core/cloud_io.hpp"
#include "core/crs_metres.hpp"
#include "core/crs_units.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory_limit.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "core/version.hpp"
#include "encode/forest_file.hpp"
#include "forestry/tile_trees.hpp"
#include "forestry/tree_pipeline.hpp"
#include "render/tile_map.hpp"
#include "segment/segment_trees.hpp"
#include "segment/terrain.hpp"
#include "survey/buffered_tile.hpp"
#include "survey/tile_list.hpp"
#include "survey/tree_id.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <set>
#include <tuple>

namespace fs = std::filesystem;

namespace treelobes::cli {

namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

struct TileCliOptions {
    std::string input;
    std::string out;
    std::string mode = "auto";
    std::string stand = "broadleaf";
    std::optional<float> max_crown_radius;  // metres; unset = the stand's
    bool use_input_segmentation = false;
    bool overwrite = false;
    std::string model;
    classify::VotingOptions voting;
    TerrainOptions terrain;
    SegmentOptions segment;
    forestry::TreePipelineOptions trees;
    double budget_kb = 39;  // each tree's .tlobe (Livny et al. 2011, Table 2: under 40 kB)
    std::string outlier_test = "auto";
    int map_px = 1600;
    double buffer = 0;       // metres; 0 = no buffer
    std::string neighbours;  // LIST|DIR|GLOB; empty = the input's folder
    double tile_size = 0;    // a retile square's side: the core from the name; 0 = from the header
    std::string max_memory;  // empty = default_memory_budget_bytes()
};

// Names of the outputs in DIR (docs/tile.md).
struct TileOutputs {
    fs::path dir, points, csv, geojson, crowns, forest, dtm, hillshade, map, summary, failures, trees;
    explicit TileOutputs(const fs::path& out)
            : dir(out),
              points(out / "points.las"),
              csv(out / "trees.csv"),
              geojson(out / "trees.geojson"),
              crowns(out / "crowns.geojson"),
              forest(out / "tile.forest"),
              dtm(out / "dtm.asc"),
              hillshade(out / "hillshade.png"),
              map(out / "top_view.png"),
              summary(out / "summary.json"),
              failures(out / "failures.jsonl"),
              trees(out / "trees") {}
    fs::path tree_file(int id, const std::string& suffix) const {
        char name[32];
        std::snprintf(name, sizeof name, "tree_%04d", id);
        return trees / (name + suffix);
    }
};

const char* kSkeletonSuffix = "_skeleton.ply";
const char* kBranchesSuffix = "_branches.ply";
const char* kTlobeSuffix = ".tlobe";
const char* kDbf6Suffix = ".dbf6";
const char* kRecordSuffix = ".json";

// The resolved options that shape the outputs (summary.json records them; the per-tree part is
// the key that lets a re-run reuse a finished tree).
json tree_options_json(const TileCliOptions& o) {
    const auto& t = o.trees;
    return {{"min_tree_points", t.min_points},
            {"outlier_test", o.outlier_test},
            {"beta", t.reconstruct.skeleton.beta},
            {"gamma", t.reconstruct.allometry.gamma},
            {"fs", t.reconstruct.allometry.fs},
            {"alpha_factor", t.lobes.alpha.alpha_factor},
            {"lobe_shape_points", t.lobes.max_shape_points},
            {"dbf6_resolution", t.dbf6.encode.resolution},
            {"dbf6_lods", t.dbf6.lods},
            {"breast_height", t.dbh.breast_height},
            {"crown_alpha_factor", t.crown.alpha_factor},
            {"model", o.model}};
}

std::string unit_text(const CrsUnit& unit) {
    char metres[32];
    std::snprintf(metres, sizeof metres, "%.6g", unit.metres);
    return unit.name + " (" + metres + " m)";
}

// Coordinates are taken as metres. A CRS in feet (US State Plane surveys) or degrees gives
// heights, crowns and DBH in its own unit and thresholds (a 2 m minimum tree height, 0.5 m CHM
// cells) that do not fit; heights in feet under metres across (a compound CRS with a vertical
// part in feet) give tree heights in feet. The run goes on, and says so.
void warn_of_units_other_than_metres(const std::string& input, const CrsUnits& units) {
    const std::optional<CrsUnit>& across = units.horizontal;
    if (across && across->angular) {
        log_warn(input +
                 ": the CRS is geographic (coordinates in degrees); treelobes takes coordinates as metres: reproject the tile "
                 "to a projected CRS in metres");
    } else if (across && !across->is_metre()) {
        log_warn(input + ": the CRS measures lengths in " + unit_text(*across) +
                 "; treelobes takes coordinates as metres, so heights, crowns and DBH come out in that unit and its thresholds "
                 "in metres do not fit: convert it first (treelobes convert TILE --out TILE_M.las --to-metres)");
        return;  // the heights' unit is said with it
    }
    if (units.vertical && !units.vertical->is_metre())
        log_warn(input + ": the CRS measures heights in " + unit_text(*units.vertical) +
                 "; treelobes takes heights as metres, so tree heights, crown bases and volumes come out in that unit and its "
                 "height thresholds in metres do not fit: convert it first (treelobes convert TILE --out TILE_M.las --to-metres)");
}

// A unit as the CRS names it (null when it names none).
json crs_unit_json(const std::optional<CrsUnit>& unit) {
    if (!unit) return nullptr;
    return {{"name", unit->name}, {"metres", unit->metres}, {"angular", unit->angular}};
}

// An airborne segmentation of a sparse survey (segment_trees.hpp, kSparseSurveyReturnSpacing).
bool sparse_survey(const TreeSegmentation& segmentation) {
    return segmentation.mode_used == ScanMode::Airborne && segmentation.return_spacing > kSparseSurveyReturnSpacing;
}

// Every flag's value, the segmentation mode the tile got, and the per-tree options.
json options_json(const OptionTable& table, const TileCliOptions& o, const TreeSegmentation& segmentation) {
    json options = table.json();
    options["mode_used"] = o.use_input_segmentation ? "input" : scan_mode_name(segmentation.mode_used);
    options["mode_reason"] = o.use_input_segmentation ? "--use-input-segmentation" : segmentation.mode_reason;
    if (!o.use_input_segmentation && segmentation.mode_used == ScanMode::Airborne)
        options["chm"] = {{"return_spacing_m", segmentation.return_spacing},
                          {"pulse_density_per_m2", segmentation.pulse_density},
                          {"sparse_survey", sparse_survey(segmentation)},
                          {"cell_m", segmentation.chm_cell},
                          {"point_radius_m", segmentation.chm_point_radius}};
    options["trees"] = tree_options_json(o);
    return options;
}

// Per-point tree ids: the input's treeID (--use-input-segmentation) or a fresh segmentation, in
// which case an input treeID is kept as `treeID_input`.
std::vector<std::int32_t> input_tree_ids(const PointCloud& cloud, const std::string& input) {
    const ExtraAttribute* attribute = cloud.extra("treeID");
    if (!attribute)
        throw Error::input(input, "--use-input-segmentation: the input has no treeID attribute (LAS extra bytes or PLY scalar_treeID)");
    std::vector<std::int32_t> ids;
    ids.reserve(cloud.size());
    for (double v : attribute->values) ids.push_back(std::isfinite(v) && v > 0 && v < 2147483647.0 ? static_cast<std::int32_t>(v) : 0);
    return ids;
}

// The input points with treeID, classification (2 = ground) and HeightAboveGround.
PointCloud labelled_points(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::int32_t>& tree_id,
                           bool fresh_segmentation) {
    PointCloud out = cloud;
    if (fresh_segmentation)
        if (ExtraAttribute* old = out.extra("treeID")) {
            old->name = "treeID_input";
            old->description = "treeID of the input";
        }
    ExtraAttribute& ids = out.add_extra("treeID", AttributeType::Int32);
    ids.description = "tree id, 0 = no tree";
    ids.values.assign(tree_id.begin(), tree_id.end());
    ExtraAttribute& hag = out.add_extra("HeightAboveGround", AttributeType::Float32);
    hag.description = "height above the DTM (m)";
    hag.values.assign(terrain.height_above_ground.begin(), terrain.height_above_ground.end());
    if (out.classification.empty()) out.classification.assign(out.size(), 1);  // ASPRS 1: unclassified
    for (std::size_t i = 0; i < out.size(); ++i) {
        if (terrain.is_ground[i])
            out.classification[i] = 2;
        else if (out.classification[i] == 2)
            out.classification[i] = 1;  // no longer ground by the DTM
    }
    return out;
}

void write_tree_products(const TileOutputs& out, const forestry::TreeOutcome& outcome, const forestry::TreeProducts& products) {
    write_skeleton_ply(products.skeleton, out.tree_file(outcome.id, kSkeletonSuffix));
    write_mesh(products.branches, out.tree_file(outcome.id, kBranchesSuffix));
    write_file_atomically(out.tree_file(outcome.id, kTlobeSuffix), products.tlobe);
    write_file_atomically(out.tree_file(outcome.id, kDbf6Suffix), std::string(products.dbf6.begin(), products.dbf6.end()));
}

bool tree_files_exist(const TileOutputs& out, int id) {
    for (const char* suffix : {kSkeletonSuffix, kBranchesSuffix, kTlobeSuffix, kDbf6Suffix, kRecordSuffix})
        if (!fs::exists(out.tree_file(id, suffix))) return false;
    return true;
}

// A finished tree of an earlier run with the same options and points, read back.
std::optional<forestry::TreeOutcome> finished_tree(const TileOutputs& out, const forestry::TreeInput& tree, const std::string& key,
                                                   std::size_t& lobes) {
    if (!tree_files_exist(out, tree.id)) return std::nullopt;
    const auto row = forestry::read_tree_record(read_file(out.tree_file(tree.id, kRecordSuffix)), key);
    if (!row || row->measures.points != tree.points.size()) return std::nullopt;
    forestry::TreeOutcome outcome;
    outcome.id = tree.id;
    outcome.ok = true;
    outcome.modelled = true;
    outcome.measures = row->measures;
    outcome.skeleton = read_skeleton_ply(out.tree_file(tree.id, kSkeletonSuffix));
    lobes = row->lobes;
    return outcome;
}

// Species names and confidences after spatial voting over the tile.
void assign_species(std::vector<forestry::TreeRow>& rows, const std::vector<forestry::TreeOutcome>& outcomes,
                    const std::vector<std::size_t>& row_of, const classify::JointBoostModel& model, const classify::VotingOptions& voting) {
    const std::vector<int> voted = forestry::vote_species(outcomes, voting);
    for (std::size_t i = 0; i < outcomes.size(); ++i) {
        if (voted[i] < 0 || row_of[i] == SIZE_MAX) continue;
        forestry::TreeRow& row = rows[row_of[i]];
        row.species = model.classes.at(static_cast<std::size_t>(voted[i]));
        row.species_confidence = outcomes[i].measures.species_probabilities.at(static_cast<std::size_t>(voted[i]));
    }
}

// Writes `path` with `write` unless it exists and --overwrite is off; says which.
template <typename Write>
bool write_output(const fs::path& path, bool overwrite, Write&& write) {
    if (!overwrite && fs::exists(path)) {
        log_info(path.string() + " exists, kept (use --overwrite to redo)");
        return false;
    }
    write();
    return true;
}

// The tile's own points whose class says they are no tree's (buildings, water, wires, noise:
// core/asprs_classes.hpp), by class name; the segmentation leaves them out, and one line says so.
json points_left_out_by_class(const PointCloud& cloud, std::size_t own_points, const std::string& input) {
    std::map<std::uint8_t, std::size_t> counts;
    for (std::size_t i = 0; i < own_points && i < cloud.classification.size(); ++i)
        if (asprs_never_a_tree(cloud.classification[i])) ++counts[cloud.classification[i]];
    json by_name = json::object();
    std::string text;
    for (const auto& [code, count] : counts) {
        by_name[asprs_class_name(code)] = count;
        text += (text.empty() ? "" : ", ") + std::to_string(count) + " " + asprs_class_name(code) + " (" + std::to_string(code) + ")";
    }
    if (!counts.empty()) log_info(input + ": points left out of the trees by their class: " + text);
    return by_name;
}

// A sparse airborne survey splits its crowns: said once, with the survey's pulse density, so
// that a user does not take the trees for what the scan can show. A spacing given for the survey
// (--return-spacing, or batch's measure on a typical tile) decides the CHM whatever this tile's
// own density, and the warning says so.
void warn_if_sparse_survey(const std::string& input, const TreeSegmentation& segmentation, bool spacing_given) {
    if (segmentation.mode_used != ScanMode::Airborne) return;
    const double pulses = segmentation.pulse_density;
    char text[480];
    if (pulses < kTooSparseForTrees)
        std::snprintf(text, sizeof text,
                      ": the survey holds about %.2g pulses per m^2 (first returns over its footprint), too few to tell single "
                      "trees apart: its trees are patches of a few returns (mean F1 0.33-0.43 on synthetic stands at "
                      "0.025-0.05 pulses per m^2; docs/segment.md, \"Sparse airborne surveys\")",
                      pulses);
    else if (sparse_survey(segmentation) && spacing_given)
        std::snprintf(text, sizeof text,
                      ": the return spacing given, %.2f m (--return-spacing, or the survey's from batch), is a sparse survey's, "
                      "fewer than about 0.5 pulses per m^2 (this tile holds about %.2g): its CHM takes discs of the whole spacing; "
                      "expect crowns split into several trees (docs/segment.md, \"Sparse airborne surveys\")",
                      static_cast<double>(segmentation.return_spacing), pulses);
    else if (sparse_survey(segmentation))
        std::snprintf(text, sizeof text,
                      ": the survey holds about %.2g pulses per m^2 (first returns over its footprint; the vegetation returns "
                      "read %.2f m apart), fewer than about 0.5: expect crowns split into several trees (mean F1 0.58-0.82 "
                      "on synthetic stands at 0.1-0.35 pulses per m^2; docs/segment.md, \"Sparse airborne surveys\")",
                      pulses, static_cast<double>(segmentation.return_spacing));
    else
        return;
    log_warn(input + text);
}

// One line for all the trees whose points look like a building's (an unclassified urban tile's
// roofs and walls), rather than a warning per tree; trees.csv marks them in `not_a_tree`.
void warn_of_trees_that_are_not(const std::string& input, const std::vector<forestry::TreeRow>& rows) {
    std::vector<int> ids;
    std::size_t assessed = 0;
    for (const forestry::TreeRow& row : rows) {
        if (!row.measures.not_a_tree) continue;
        ++assessed;
        if (*row.measures.not_a_tree) ids.push_back(row.measures.id);
    }
    if (ids.empty()) return;
    constexpr std::size_t kIdsNamed = 10;
    std::string named;
    for (std::size_t k = 0; k < std::min(ids.size(), kIdsNamed); ++k) named += (k ? ", " : "") + std::to_string(ids[k]);
    if (ids.size() > kIdsNamed) named += ", ...";
    log_warn(input + ": " + std::to_string(ids.size()) + " of " + std::to_string(assessed) +
             " modelled trees do not look like trees (wide planes: roofs, walls; trees.csv column not_a_tree): " + named);
}

std::string dbh_counts(const std::vector<forestry::TreeRow>& rows, json& counts) {
    std::map<std::string, int> by_quality{{"ok", 0}, {"partial_arc", 0}, {"not_visible", 0}};
    for (const auto& row : rows) ++by_quality[forestry::dbh_quality_name(row.measures.dbh.quality)];
    counts = by_quality;
    return std::to_string(by_quality["ok"]) + " ok, " + std::to_string(by_quality["partial_arc"]) + " partial arc, " +
           std::to_string(by_quality["not_visible"]) + " not visible";
}

// The tile's buffer plan: its core and the files that may hold its buffer points.
struct BufferPlan {
    std::optional<survey::TileCore> core;  // from the retile name or the header; else from the points once read
    std::vector<fs::path> candidates;
};

BufferPlan plan_buffer(const TileCliOptions& o) {
    if (o.buffer <= 0) {
        if (!o.neighbours.empty() || o.tile_size > 0) throw Error::usage("--neighbours and --tile-size go with --buffer METRES");
        return {};
    }
    BufferPlan plan;
    plan.core = o.tile_size > 0 ? survey::core_from_retile_name(o.input, o.tile_size) : survey::core_from_header(o.input);
    const fs::path folder = fs::path(o.input).parent_path();
    plan.candidates = survey::list_tiles(o.neighbours.empty() ? (folder.empty() ? std::string(".") : folder.string()) : o.neighbours);
    return plan;
}

// Refuses the tile before it is read when its points (and its buffer's) would not fit in --max-memory.
void check_tile_memory(const TileCliOptions& o, const BufferPlan& plan) {
    const double budget = o.max_memory.empty() ? default_memory_budget_bytes() : parse_memory_size(o.max_memory);
    std::size_t points = header_point_count(o.input);
    if (o.buffer > 0) points += survey::estimate_buffer_points(o.input, plan.core, o.buffer, plan.candidates);
    if (const auto refusal = memory_refusal(points, kTileBytesPerPoint, budget)) throw Error::input(o.input, *refusal);
}

// Keeps the trees whose stem base lies in the core; the others (their base in the buffer) are
// the neighbours' and lose their ids here. Returns how many were dropped.
std::size_t keep_core_trees(std::vector<forestry::TreeInput>& trees, std::vector<std::int32_t>& tree_id, const survey::TileCore& core,
                            const Eigen::Vector3d& origin) {
    std::set<std::int32_t> dropped;
    std::vector<forestry::TreeInput> kept;
    for (forestry::TreeInput& tree : trees) {
        const Eigen::Vector3d base = origin + tree.base;
        if (core.holds(base.x(), base.y()))
            kept.push_back(std::move(tree));
        else
            dropped.insert(tree.id);
    }
    trees = std::move(kept);
    for (std::int32_t& id : tree_id)
        if (dropped.count(id)) id = 0;
    return dropped.size();
}

// A tree's points in the order of their coordinates (x, then y, then z), so that its model does
// not depend on where its points sat in the file: a tree read whole from a buffer (its points
// from several files) is modelled as in one file.
void order_points_by_position(forestry::TreeInput& tree) {
    std::vector<std::size_t> order(tree.points.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    const auto& p = tree.points.positions;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return std::make_tuple(p[a].x(), p[a].y(), p[a].z()) < std::make_tuple(p[b].x(), p[b].y(), p[b].z());
    });
    std::vector<float> heights(order.size());
    for (std::size_t k = 0; k < order.size(); ++k) heights[k] = tree.height_above_ground[order[k]];
    tree.points = tree.points.subset(order);
    tree.height_above_ground = std::move(heights);
}

// Survey-wide ids of the trees (by tile tree id), from their stem bases.
std::map<int, std::string> survey_ids(const std::vector<forestry::TreeInput>& trees, const Eigen::Vector3d& origin) {
    std::vector<Eigen::Vector3d> bases;
    for (const auto& tree : trees) bases.push_back(origin + tree.base);
    const std::vector<std::string> ids = survey::stable_tree_ids(bases);
    std::map<int, std::string> by_tree;
    for (std::size_t i = 0; i < trees.size(); ++i) by_tree[trees[i].id] = ids[i];
    return by_tree;
}

// The survey-wide ids of the kept trees that have points within `margin` of the buffer's outer
// edge. Points lie there only where a neighbouring tile gave them, so such a tree may go on
// beyond the buffer and be cut: its crown, height and model would then differ from an uncut run.
std::vector<std::string> trees_at_buffer_edge(const std::vector<forestry::TreeInput>& trees, const survey::TileCore& core, double buffer,
                                              const Eigen::Vector3d& origin, const std::map<int, std::string>& global_ids) {
    constexpr double kMargin = 0.5;  // metres: about twice the point spacing of a 20 pulses/m² airborne scan
    const Box3d box = survey::buffered_box(core, buffer);
    const auto at_edge = [&](const Eigen::Vector3f& local) {
        const Eigen::Vector3d p = origin + local.cast<double>();
        return p.x() < box.min.x() + kMargin || p.x() > box.max.x() - kMargin || p.y() < box.min.y() + kMargin ||
               p.y() > box.max.y() - kMargin;
    };
    std::vector<std::string> ids;
    for (const forestry::TreeInput& tree : trees)
        if (std::any_of(tree.points.positions.begin(), tree.points.positions.end(), at_edge)) ids.push_back(global_ids.at(tree.id));
    std::sort(ids.begin(), ids.end());
    return ids;
}

void warn_of_trees_at_buffer_edge(const TileCliOptions& o, const std::vector<std::string>& ids) {
    if (ids.empty()) return;
    log_warn(o.input + ": " + std::to_string(ids.size()) + (ids.size() == 1 ? " tree reaches" : " trees reach") +
             " the outer edge of the " + summary_value(o.buffer).dump() + " m buffer and may be cut there (" + ids.front() +
             (ids.size() > 1 ? ", ..." : "") + "; all in summary.json, buffer.trees_at_edge): a wider --buffer keeps them whole");
}

// The airborne segmentation's reach (segment_trees.hpp) when the tile's trees come from one;
// null for terrestrial plots and the input's labels.
std::optional<float> segmentation_reach(const TileCliOptions& o, const TreeSegmentation& segmentation) {
    if (o.use_input_segmentation || segmentation.mode_used != ScanMode::Airborne) return std::nullopt;
    return airborne_reach(o.segment);
}

// A buffer narrower than the segmentation's reach: trees near the tile's edges may come out
// otherwise than from the uncut survey. Said once per process (a batch runs many tiles).
void warn_if_buffer_is_narrow(const TileCliOptions& o, std::optional<float> reach) {
    static std::once_flag said;
    if (o.buffer <= 0 || !reach || o.buffer >= *reach) return;
    std::call_once(said, [&] {
        log_warn("--buffer " + summary_value(o.buffer).dump() + " m is narrower than the airborne segmentation's reach (" +
                 summary_value(*reach).dump() +
                 " m, twice --max-crown-radius and the CHM smoothing): crowns near the tile's edges may differ from a run on the uncut "
                 "survey "
                 "(docs/survey.md)");
    });
}

json buffer_json(const TileCliOptions& o, const BufferPlan& plan, const survey::BufferedTile& buffered, std::optional<float> reach,
                 const std::vector<std::string>& trees_at_edge) {
    if (!plan.core) return nullptr;
    json read = json::array();
    for (const fs::path& file : buffered.neighbours_read) read.push_back(file.filename().string());
    const survey::TileCore& c = *plan.core;
    return {{"metres", o.buffer},
            {"core",
             {{"min_x", c.min_x},
              {"min_y", c.min_y},
              {"max_x", c.max_x},
              {"max_y", c.max_y},
              {"from", c.source},
              {"half_open", c.half_open}}},
            {"neighbours_read", read},
            {"neighbours_skipped", buffered.neighbours_skipped},
            {"segmentation_reach_m", summary_value(reach)},
            {"wide_enough", reach ? json(o.buffer >= *reach) : json(nullptr)},
            {"trees_at_edge", trees_at_edge}};
}

int run_tile(TileCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    const auto start = Clock::now();
    auto mark = start;
    json seconds = json::object();
    o.segment.mode = parse_scan_mode(o.mode);
    o.segment = with_stand_type(o.segment, parse_stand_type(o.stand));
    if (o.max_crown_radius) o.segment.max_crown_radius = *o.max_crown_radius;
    o.trees.reconstruct.preprocess.outlier_test = parse_outlier_test(o.outlier_test);
    o.trees.reconstruct.preprocess.ground = GroundMode::Keep;  // the terrain stage removed the ground already
    o.trees.tlobe.max_bytes = static_cast<std::size_t>(o.budget_kb * 1000);
    std::optional<classify::JointBoostModel> model;
    if (!o.model.empty()) {
        model = classify::load_jointboost(o.model);
        o.trees.model = &*model;
    }
    BufferPlan plan = plan_buffer(o);
    check_tile_memory(o, plan);
    const TileOutputs out(o.out);
    std::error_code ec;
    fs::create_directories(out.trees, ec);
    if (!fs::is_directory(out.trees)) throw Error::usage("--out " + o.out + ": cannot create the output folder");

    survey::BufferedTile buffered;
    buffered.cloud = read_point_cloud(o.input);
    if (buffered.cloud.empty()) throw Error::input(o.input, "the tile holds no points");
    if (buffered.cloud.georef.empty()) log_warn(o.input + ": no CRS in the input; outputs keep its coordinates without one");
    warn_of_units_other_than_metres(o.input, crs_units_of(buffered.cloud.georef));
    buffered.own_points = buffered.cloud.size();
    if (o.buffer > 0) {
        if (!plan.core) plan.core = survey::core_from_points(buffered.cloud);
        buffered = survey::add_buffer(std::move(buffered.cloud), o.input, *plan.core, o.buffer, plan.candidates);
    }
    const PointCloud& cloud = buffered.cloud;
    seconds["read"] = rounded(lap_seconds(mark));
    const json left_out = points_left_out_by_class(cloud, buffered.own_points, o.input);

    const Terrain terrain = analyse_terrain(cloud, o.terrain);
    seconds["terrain"] = rounded(lap_seconds(mark));
    TreeSegmentation segmentation;
    std::map<int, Eigen::Vector3d> bases;
    if (o.use_input_segmentation) {
        segmentation.tree_id = input_tree_ids(cloud, o.input);
    } else {
        segmentation = segment_trees(cloud, terrain, o.segment);
        for (const auto& tree : segmentation.trees) bases[tree.id] = tree.base.cast<double>();
        warn_if_sparse_survey(o.input, segmentation, o.segment.return_spacing > 0.0f);
    }
    const std::optional<float> reach = segmentation_reach(o, segmentation);
    if (plan.core) warn_if_buffer_is_narrow(o, reach);
    const bool bases_at_stems = segmentation.mode_used != ScanMode::Airborne;  // terrestrial: stem circles
    std::vector<forestry::TreeInput> trees =
            forestry::split_trees(cloud, segmentation.tree_id, terrain.height_above_ground, bases, bases_at_stems);
    const std::size_t trees_in_buffer = plan.core ? keep_core_trees(trees, segmentation.tree_id, *plan.core, cloud.origin) : 0;
    const std::map<int, std::string> global_ids = survey_ids(trees, cloud.origin);
    const std::vector<std::string> trees_at_edge =
            plan.core ? trees_at_buffer_edge(trees, *plan.core, o.buffer, cloud.origin, global_ids) : std::vector<std::string>{};
    warn_of_trees_at_buffer_edge(o, trees_at_edge);
    for (forestry::TreeInput& tree : trees) order_points_by_position(tree);
    seconds["segmentation"] = rounded(lap_seconds(mark));
    if (trees.empty())
        log_warn(o.input + ": no trees found (" + std::to_string(terrain.ground_points) + " of " + std::to_string(cloud.size()) +
                 " points are ground); the outputs list none");

    // Trees finished by an earlier run are read back; the others go through the pipeline.
    const json options = options_json(table, o, segmentation);
    const std::string key = "treelobes " + std::string(kVersion) + ", records " + std::to_string(forestry::kTreeRecordRevision) + ", " +
                            tree_options_json(o).dump();
    std::vector<forestry::TreeOutcome> outcomes(trees.size());
    std::vector<std::size_t> lobe_counts(trees.size(), 0);
    std::vector<forestry::TreeInput> todo;
    std::vector<std::size_t> todo_index;
    for (std::size_t i = 0; i < trees.size(); ++i) {
        std::optional<forestry::TreeOutcome> done = o.overwrite ? std::nullopt : finished_tree(out, trees[i], key, lobe_counts[i]);
        if (done) {
            outcomes[i] = std::move(*done);
        } else {
            todo.push_back(std::move(trees[i]));
            todo_index.push_back(i);
        }
    }
    const std::size_t reused = trees.size() - todo.size();
    if (reused > 0) log_info(std::to_string(reused) + " trees finished by an earlier run are kept (use --overwrite to redo them)");
    std::map<int, std::size_t> position_of;
    for (std::size_t k = 0; k < todo.size(); ++k) position_of[todo[k].id] = todo_index[k];
    json stage_seconds = json::object();
    {
        Progress progress("trees", todo.size());
        const auto made =
                forestry::process_trees(todo, o.trees, [&](const forestry::TreeOutcome& outcome, const forestry::TreeProducts* products) {
                    if (products) {
                        write_tree_products(out, outcome, *products);
                        lobe_counts[position_of.at(outcome.id)] = products->lobes;
                    }
                    for (const auto& [stage, s] : outcome.seconds) stage_seconds[stage] = stage_seconds.value(stage, 0.0) + s;
                    progress.advance();
                });
        progress.finish();
        for (std::size_t k = 0; k < made.size(); ++k) outcomes[todo_index[k]] = made[k];
    }
    todo.clear();
    seconds["trees"] = rounded(lap_seconds(mark));
    for (auto& [stage, s] : stage_seconds.items()) s = rounded(s.get<double>());
    seconds["tree_stages_summed"] = stage_seconds;

    // Rows of the finished trees (ids ascending), species by spatial voting, failures.
    std::vector<forestry::TreeRow> rows;
    std::vector<std::size_t> row_of(outcomes.size(), SIZE_MAX);
    json failures = json::array();
    std::vector<encode::ForestTree> forest;
    std::vector<render::TileMapStem> stems;
    for (std::size_t i = 0; i < outcomes.size(); ++i) {
        const auto& outcome = outcomes[i];
        if (!outcome.ok) {
            failures.push_back(
                    {{"tree_id", outcome.id}, {"reason", outcome.failure}, {"exit_code", static_cast<int>(outcome.failure_code)}});
            continue;
        }
        row_of[i] = rows.size();
        rows.push_back({outcome.measures, {}, std::nullopt, lobe_counts[i], outcome.modelled, global_ids.at(outcome.id)});
        stems.push_back({outcome.id, outcome.measures.position, outcome.measures.not_a_tree.value_or(false)});
        if (!outcome.modelled) continue;
        encode::ForestTree placed;
        placed.skeleton = outcome.skeleton;
        const Eigen::Vector3d root = placed.skeleton.origin + placed.skeleton.nodes[0].position.cast<double>();
        placed.skeleton.origin = -placed.skeleton.nodes[0].position.cast<double>();
        placed.position = root;
        placed.name = "tree_" + std::to_string(outcome.id);
        forest.push_back(std::move(placed));
    }
    if (model) assign_species(rows, outcomes, row_of, *model, o.voting);
    warn_of_trees_that_are_not(o.input, rows);
    for (std::size_t i : todo_index)  // after the tree's files: a record marks a finished tree
        if (row_of[i] != SIZE_MAX && rows[row_of[i]].modelled)
            write_file_atomically(out.tree_file(outcomes[i].id, kRecordSuffix), forestry::tree_record(rows[row_of[i]], cloud.origin, key));
    seconds["species"] = rounded(lap_seconds(mark));

    // Tile outputs.
    write_output(out.points, o.overwrite, [&] {
        const PointCloud labelled = labelled_points(cloud, terrain, segmentation.tree_id, !o.use_input_segmentation);
        if (labelled.size() == buffered.own_points) {
            write_las(labelled, out.points);
        } else {  // the tile's own points only: the buffer's are its neighbours'
            std::vector<std::size_t> own(buffered.own_points);
            std::iota(own.begin(), own.end(), std::size_t{0});
            write_las(labelled.subset(own), out.points);
        }
    });
    write_file_atomically(out.csv, forestry::trees_csv(rows, cloud.origin));
    write_file_atomically(out.geojson, forestry::trees_geojson(rows, cloud.origin, cloud.georef.crs_wkt));
    write_file_atomically(out.crowns, forestry::crowns_geojson(rows, cloud.origin, cloud.georef.crs_wkt));
    encode::write_forest_file(forest, o.trees.dbf6, out.forest);
    write_output(out.dtm, o.overwrite, [&] { write_ascii_grid(terrain.dtm, cloud.origin, out.dtm); });
    write_output(out.hillshade, o.overwrite, [&] { write_hillshade_png(terrain.dtm, out.hillshade); });
    write_output(out.map, o.overwrite, [&] {
        render::TileMapOptions map;
        map.max_side_px = o.map_px;
        render::write_png(render::draw_tile_map(cloud, segmentation.tree_id, terrain.height_above_ground, stems, map), out.map);
    });
    if (!failures.empty()) {
        std::string lines;
        for (const auto& f : failures) lines += f.dump() + "\n";
        write_file_atomically(out.failures, lines);
    } else {
        fs::remove(out.failures, ec);  // a failure list of an earlier run no longer holds
    }
    seconds["outputs"] = rounded(lap_seconds(mark));
    seconds["total"] = rounded(seconds_since(start));

    json dbh = json::object();
    const std::string dbh_text = dbh_counts(rows, dbh);
    std::size_t tree_points = 0, modelled = 0;
    for (const auto& row : rows) {
        tree_points += row.measures.points;
        modelled += row.modelled ? 1 : 0;
    }
    const json summary = {{"treelobes", kVersion},
                          {"command", "tile"},
                          {"input", o.input},
                          {"out", o.out},
                          {"options", options},
                          {"buffer", buffer_json(o, plan, buffered, reach, trees_at_edge)},
                          {"counts",
                           {{"points", buffered.own_points},
                            {"buffer_points", cloud.size() - buffered.own_points},
                            {"non_finite_dropped", cloud.source.dropped_non_finite},
                            {"trees_in_buffer", trees_in_buffer},
                            {"ground_points", terrain.ground_points},
                            {"ground_source", terrain.ground_source},
                            {"left_out_by_class", left_out},
                            {"tree_points", tree_points},
                            {"trees_found", outcomes.size()},
                            {"trees", rows.size()},
                            {"trees_modelled", modelled},
                            {"trees_measured_only", rows.size() - modelled},
                            {"trees_reused", reused},
                            {"trees_failed", failures.size()},
                            {"dbh", dbh}}},
                          {"crs", cloud.georef.empty() ? json(nullptr) : json(cloud.georef.crs_wkt)},
                          {"crs_unit", crs_unit_json(crs_units_of(cloud.georef).horizontal)},
                          {"crs_vertical_unit", crs_unit_json(crs_units_of(cloud.georef).vertical)},
                          {"outputs",
                           {{"points", out.points.string()},
                            {"trees_csv", out.csv.string()},
                            {"trees_geojson", out.geojson.string()},
                            {"crowns_geojson", out.crowns.string()},
                            {"forest", out.forest.string()},
                            {"dtm", out.dtm.string()},
                            {"hillshade", out.hillshade.string()},
                            {"top_view", out.map.string()},
                            {"trees", out.trees.string()},
                            {"failures", failures.empty() ? json(nullptr) : json(out.failures.string())}}},
                          {"seconds", seconds},
                          {"peak_memory_mb", rounded(peak_memory_mb(), 1)}};
    write_file_atomically(out.summary, summary.dump(2) + "\n");
    if (global.json) {
        std::cout << summary.dump(2) << "\n";
    } else {
        const std::string failure_note = failures.empty() ? "" : " (" + out.failures.string() + ")";
        // The preset is named: no automatic choice tells dense conifers from broad crowns
        // (docs/segment.md), and the wrong one loses most trees.
        const std::string stand_note = o.use_input_segmentation ? "" : " (" + o.stand + " stand)";
        std::printf(
                "%s: %zu points, %zu ground (%s); %s segmentation%s: %zu trees found, %zu modelled, %zu measured only (fewer than %zu "
                "points), %zu failed%s\n",
                o.input.c_str(), cloud.size(), terrain.ground_points, terrain.ground_source.c_str(),
                options["mode_used"].get<std::string>().c_str(), stand_note.c_str(), outcomes.size(), modelled, rows.size() - modelled,
                o.trees.min_points, failures.size(), failure_note.c_str());
        std::printf("DBH: %s; %.1f s, peak memory %.0f MB\n", dbh_text.c_str(), seconds["total"].get<double>(), peak_memory_mb());
        std::printf("trees: %s and %s, crown outlines: %s; picture: %s\n", out.csv.string().c_str(), out.geojson.string().c_str(),
                    out.crowns.string().c_str(), out.map.string().c_str());
    }
    return failures.empty() ? 0 : static_cast<int>(ExitCode::PartialFailure);
}

}  // namespace

void add_tile_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto o = std::make_shared<TileCliOptions>();
    // A tile has hundreds of trees: lobes from at most 2,000 grid-thinned points each (the single-tree
    // `lobes` command takes 6,000), which keeps the alpha shapes, the slowest per-tree stage, affordable.
    o->trees.lobes.max_shape_points = 2000;
    CLI::App* sub = app.add_subcommand(
            "tile",
            "A LiDAR tile in, every tree out: ground and DTM, tree segmentation, per-tree skeleton, lobes, DBF6, measures "
            "(height, DBH, crown), species; tables, crown outlines, LAS with treeID, forest file and a top-view picture (docs/tile.md)");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("input", o->input, "The tile: LAS 1.0-1.4, LAZ or COPC, PLY, PCD or XYZ/CSV")->required();
    table->add("--out", o->out, "Output folder")->required();
    table->add("--mode", o->mode,
               "Segmentation: als (canopy height model, treetops, crowns), tls (stems, plot-wide shortest "
               "paths) or auto (from the point density)")
            ->check(CLI::IsMember({"auto", "als", "tls"}));
    table->add("--stand", o->stand,
               "Stand type: broadleaf (airborne: broad crowns, many maxima merged; terrestrial: thick trunks reach farther) or "
               "conifer (dense conifer stands; airborne: every treetop a tree, crowns at most 3.5 m from their top; terrestrial: all "
               "stems reach alike)")
            ->check(CLI::IsMember({"broadleaf", "conifer"}));
    table->add("--max-crown-radius", o->max_crown_radius,
               "Airborne: no crown reaches farther from its treetop, metres (default: the stand's, 15 broadleaf, 3.5 conifer)")
            ->check(PositiveNumber);
    table->add("--return-spacing", o->segment.return_spacing,
               "Airborne: mean spacing of the survey's vegetation returns, metres, from which the CHM's cell and discs grow (0 = "
               "estimated per tile; give the tiles of one survey one value so that they draw the same CHM)")
            ->check(NonNegativeNumber)
            ->check(CLI::Range(0.0, 10.0));
    table->add_flag("--use-input-segmentation", o->use_input_segmentation,
                    "Take the input's treeID attribute as the trees (lidR or an earlier run) instead of segmenting afresh");
    table->add("--model", o->model, "Species model (.jb from `classify train`): species per tree with spatial voting");
    table->add("--vote-radius", o->voting.radius_m, "Spatial voting neighbourhood, metres")->check(NonNegativeNumber);
    table->add("--vote-confidence", o->voting.confidence_factor, "A tree is confident when h1 > factor * h2")
            ->check(CLI::Range(1.0, 100.0));
    table->add("--dtm-cell", o->terrain.cell_size, "DTM cell size, metres")->check(PositiveNumber);
    table->add("--min-tree-height", o->segment.min_tree_height, "Lower tops are not trees, metres above ground")->check(PositiveNumber);
    table->add("--min-tree-points", o->trees.min_points,
               "Trees with fewer points are measured (a row in trees.csv) but not modelled (no skeleton, lobes or DBF6)")
            ->check(CLI::Range(10, 100000000));
    table->add("--outlier-test", o->outlier_test, "Outlier test of the per-tree reconstruction: auto, global, local")
            ->check(CLI::IsMember({"auto", "global", "local"}));
    table->add("--lobe-shape-points", o->trees.lobes.max_shape_points,
               "Larger lobe clusters are thinned on a grid to this many points before their alpha shape")
            ->check(CLI::Range(100, 10000000));
    table->add("--budget-kb", o->budget_kb,
               "Size each tree's .tlobe may take (kB); its lobe surfaces are simplified, then its occupancy grid coarsened, to fit")
            ->check(CLI::Range(2.0, 10000.0));
    table->add("--resolution", o->trees.dbf6.encode.resolution, "DBF6 voxels per internode length (r)")->check(CLI::Range(1.0, 64.0));
    table->add("--lods", o->trees.dbf6.lods, "Levels of detail in each .dbf6 and the .forest")->check(CLI::Range(1, 16));
    table->add("--map-size", o->map_px, "Longer side of top_view.png, pixels")->check(CLI::Range(200, 20000));
    table->add("--buffer", o->buffer,
               "Also read the neighbouring tiles' points within this many metres of the tile's core; the tile keeps the trees whose stem "
               "base lies in its core (docs/survey.md)")
            ->check(NonNegativeNumber);
    table->add("--neighbours", o->neighbours,
               "With --buffer: the neighbouring tiles, a folder, a quoted pattern or a list file (default: the tile's folder)");
    table->add("--tile-size", o->tile_size,
               "With --buffer: the tile is a `retile` square of this side, its core [x, x+size) x [y, y+size) from its name "
               "<prefix>_<x>_<y> (default: the header's bounds)")
            ->check(PositiveNumber);
    table->add("--max-memory", o->max_memory,
               "Refuse the tile before reading it when its header point count (buffer included) needs more memory than this (e.g. 8G; "
               "default: half of the RAM)");
    table->add_flag("--overwrite", o->overwrite, "Redo outputs and trees that exist from an earlier run");
    sub->callback([o, table, &global, &job] { job = [o, table, &global] { return run_tile(*o, *table, global); }; });
}

}  // namespace treelobes::cli
