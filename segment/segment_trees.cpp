#include "segment/segment_trees.hpp"

#include "core/error.hpp"
#include "segment/airborne_crowns.hpp"
#include "segment/terrestrial_paths.hpp"
#include "segment/tree_labels.hpp"

#include <cmath>
#include <cstdio>
#include <string>

namespace treelobes {

namespace {

void check_options(const SegmentOptions& o) {
    const auto positive = [](float v, const char* name) {
        if (!(v > 0.0f) || !std::isfinite(v)) throw Error::usage(std::string("segment: ") + name + " must be > 0");
    };
    const auto share = [](float v, const char* name) {
        if (!(v >= 0.0f && v <= 1.0f)) throw Error::usage(std::string("segment: ") + name + " must be in 0..1");
    };
    if (!(o.min_tree_height >= 0.0f) || !std::isfinite(o.min_tree_height)) throw Error::usage("segment: min tree height must be >= 0");
    positive(o.terrestrial_density, "terrestrial density");
    positive(o.chm_cell, "CHM cell");
    if (!(o.point_radius >= 0.0f) || !std::isfinite(o.point_radius)) throw Error::usage("segment: point radius must be >= 0");
    // A cell or disc of several spacings would blur neighbouring crowns into one.
    if (!(o.cell_per_spacing >= 0.0f && o.cell_per_spacing <= 4.0f)) throw Error::usage("segment: cell per spacing must be in 0..4");
    if (!(o.disc_per_spacing >= 0.0f && o.disc_per_spacing <= 4.0f)) throw Error::usage("segment: disc per spacing must be in 0..4");
    if (!(o.sparse_disc_per_spacing >= 0.0f && o.sparse_disc_per_spacing <= 4.0f))
        throw Error::usage("segment: sparse disc per spacing must be in 0..4");
    // Returns 10 m apart (0.01 per m^2) no longer show a crown.
    if (!(o.return_spacing >= 0.0f && o.return_spacing <= 10.0f)) throw Error::usage("segment: return spacing must be in 0..10 metres");
    positive(o.pit_depth, "pit depth");
    if (!(o.chm_smoothing >= 0.0f) || !std::isfinite(o.chm_smoothing)) throw Error::usage("segment: CHM smoothing must be >= 0");
    positive(o.window_base, "window base");
    if (!(o.window_per_metre >= 0.0f) || !std::isfinite(o.window_per_metre)) throw Error::usage("segment: window per metre must be >= 0");
    positive(o.max_window, "max window");
    if (!(o.min_top_prominence >= 0.0f) || !std::isfinite(o.min_top_prominence))
        throw Error::usage("segment: min top prominence must be >= 0");
    share(o.top_prominence_ratio, "top prominence ratio");
    share(o.merge_pass_ratio, "merge pass ratio");
    share(o.seed_ratio, "seed ratio");
    share(o.crown_ratio, "crown ratio");
    positive(o.max_crown_radius, "max crown radius");
    if (!(o.stem_slice_high > o.stem_slice_low) || !std::isfinite(o.stem_slice_low) || !std::isfinite(o.stem_slice_high))
        throw Error::usage("segment: the stem slice needs low < high");
    positive(o.stem_cluster_distance, "stem cluster distance");
    if (!(o.stem_subcluster_distance >= 0.0f && o.stem_subcluster_distance < o.stem_cluster_distance))
        throw Error::usage("segment: stem subcluster distance must be >= 0 and below the stem cluster distance");
    if (!(o.stem_merge_distance >= 0.0f) || !std::isfinite(o.stem_merge_distance))
        throw Error::usage("segment: stem merge distance must be >= 0");
    if (!(o.shared_top_stem_distance >= 0.0f) || !std::isfinite(o.shared_top_stem_distance))
        throw Error::usage("segment: shared top stem distance must be >= 0");
    if (!(o.shared_top_distance >= 0.0f) || !std::isfinite(o.shared_top_distance))
        throw Error::usage("segment: shared top distance must be >= 0");
    if (o.min_stem_points < 5) throw Error::usage("segment: min stem points must be >= 5");
    positive(o.min_stem_radius, "min stem radius");
    if (!(o.max_stem_radius > o.min_stem_radius)) throw Error::usage("segment: max stem radius must exceed min stem radius");
    positive(o.stem_foot_reach, "stem foot reach");
    if (!(o.buttressed_stem_radius >= 0.0f) || !std::isfinite(o.buttressed_stem_radius))
        throw Error::usage("segment: buttressed stem radius must be >= 0");
    positive(o.buttressed_foot_reach, "buttressed foot reach");
    positive(o.circle_tolerance, "circle tolerance");
    share(o.min_circle_inliers, "min circle inliers");
    share(o.min_arc_coverage, "min arc coverage");
    if (!(o.max_stem_lean >= 0.0f && o.max_stem_lean < 90.0f)) throw Error::usage("segment: max stem lean must be in 0..90 degrees");
    if (!(o.min_quarter_arc_share >= 0.0f && o.min_quarter_arc_share <= 1.0f))
        throw Error::usage("segment: min quarter arc share must be in 0..1");
    // Thinner layers than a few centimetres hold too few points for a circle, and a layer count
    // of slice height / layer height must stay small.
    if (!(o.stem_layer_height >= 0.05f && o.stem_layer_height <= 10.0f))
        throw Error::usage("segment: stem layer height must be in 0.05..10 metres");
    if (!(o.trunk_layer_height >= 0.05f && o.trunk_layer_height <= 10.0f))
        throw Error::usage("segment: trunk layer height must be in 0.05..10 metres");
    positive(o.graph_voxel, "graph voxel");
    if (o.graph_neighbours < 2 || o.graph_neighbours > 64) throw Error::usage("segment: graph neighbours must be in 2..64");
    positive(o.max_gap, "max gap");
    if (!(o.attach_gap >= 0.0f) || !std::isfinite(o.attach_gap)) throw Error::usage("segment: attach gap must be >= 0");
    if (!(o.detached_min_height >= 0.0f) || !std::isfinite(o.detached_min_height))
        throw Error::usage("segment: detached min height must be >= 0");
    if (o.min_detached_voxels < 1) throw Error::usage("segment: min detached voxels must be >= 1");
    positive(o.graph_beta, "graph beta");
    if (!(o.stem_reach_exponent >= 0.0f && o.stem_reach_exponent <= 4.0f))
        throw Error::usage("segment: stem reach exponent must be in 0..4");
    if (!(o.ground_clearance >= 0.0f) || !std::isfinite(o.ground_clearance)) throw Error::usage("segment: ground clearance must be >= 0");
}

void check_terrain_of(const PointCloud& cloud, const Terrain& terrain) {
    if (terrain.height_above_ground.size() != cloud.size() || terrain.is_ground.size() != cloud.size())
        throw Error(ExitCode::Internal, "segment: the terrain was computed for another cloud (" +
                                                std::to_string(terrain.height_above_ground.size()) + " heights for " +
                                                std::to_string(cloud.size()) + " points)");
}

std::string format(const char* pattern, double a, double b = 0, double c = 0) {
    char text[256];
    std::snprintf(text, sizeof text, pattern, a, b, c);
    return text;
}
// Airborne or terrestrial from the density of the vegetation points over the occupied 1 m cells:
// an airborne survey gives 1-100 points per square metre, a terrestrial scan hundreds to thousands.
ScanMode choose_mode(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation, const SegmentOptions& options,
                     std::string& reason) {
    const OccupiedCells occupied = occupied_cells(cloud, vegetation, 1.0f);
    const double density = occupied.density(1.0);
    const bool terrestrial = density >= options.terrestrial_density;
    reason = format("automatic: %.0f vegetation points per m^2 over %.0f occupied m^2 ", density, static_cast<double>(occupied.cells)) +
             (terrestrial ? ">= " : "< ") + format("%.0f", options.terrestrial_density) +
             (terrestrial ? " (dense: terrestrial)" : " (sparse: airborne)");
    return terrestrial ? ScanMode::Terrestrial : ScanMode::Airborne;
}

}  // namespace

const char* scan_mode_name(ScanMode mode) {
    switch (mode) {
        case ScanMode::Automatic:
            return "auto";
        case ScanMode::Airborne:
            return "als";
        case ScanMode::Terrestrial:
            return "tls";
    }
    return "auto";
}

ScanMode parse_scan_mode(std::string_view text) {
    if (text == "auto") return ScanMode::Automatic;
    if (text == "als") return ScanMode::Airborne;
    if (text == "tls") return ScanMode::Terrestrial;
    throw Error::usage("unknown scan mode '" + std::string(text) + "': expected auto, als or tls");
}

StandType parse_stand_type(std::string_view text) {
    if (text == "broadleaf") return StandType::Broadleaf;
    if (text == "conifer") return StandType::Conifer;
    throw Error::usage("unknown stand type '" + std::string(text) + "': expected broadleaf or conifer");
}

float airborne_reach(const SegmentOptions& options) { return 2.0f * (options.max_crown_radius + 3.0f * options.chm_smoothing); }

SegmentOptions with_stand_type(SegmentOptions options, StandType stand) {
    const SegmentOptions broadleaf;
    options.min_top_prominence = stand == StandType::Conifer ? 0.0f : broadleaf.min_top_prominence;
    options.top_prominence_ratio = stand == StandType::Conifer ? 0.0f : broadleaf.top_prominence_ratio;
    options.chm_smoothing = stand == StandType::Conifer ? 0.0f : broadleaf.chm_smoothing;
    options.max_crown_radius = stand == StandType::Conifer ? 3.5f : broadleaf.max_crown_radius;
    options.stem_reach_exponent = stand == StandType::Conifer ? 0.0f : broadleaf.stem_reach_exponent;
    return options;
}

float vegetation_return_spacing(const PointCloud& cloud, const Terrain& terrain, const SegmentOptions& options) {
    check_options(options);
    check_terrain_of(cloud, terrain);
    return return_spacing_of(cloud, vegetation_points(cloud, terrain, options.ground_clearance));
}

TreeSegmentation segment_trees(const PointCloud& cloud, const Terrain& terrain, const SegmentOptions& options) {
    check_options(options);
    check_terrain_of(cloud, terrain);
    TreeSegmentation result;
    result.tree_id.assign(cloud.size(), 0);
    const std::vector<std::uint8_t> vegetation = vegetation_points(cloud, terrain, options.ground_clearance);
    if (options.mode == ScanMode::Automatic) {
        result.mode_used = choose_mode(cloud, vegetation, options, result.mode_reason);
    } else {
        result.mode_used = options.mode;
        result.mode_reason = std::string("requested: ") + scan_mode_name(options.mode);
    }
    if (cloud.empty()) return result;
    if (result.mode_used == ScanMode::Terrestrial)
        segment_terrestrial(cloud, terrain, vegetation, options, result);
    else
        segment_airborne(cloud, terrain, vegetation, options, result);
    return result;
}

}  // namespace treelobes
