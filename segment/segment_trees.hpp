// Individual tree segmentation of a tile (after analyse_terrain).
//
// Airborne scans see crowns from above: a pit-free canopy height model (highest point per cell
// with each point drawn as a small disc, pits filled from their neighbours' median, Ben-Arie et
// al. 2009), treetops as local maxima in a window that widens with height (Popescu & Wynne 2004,
// §2.4) on a smoothed CHM, tops merged into a higher neighbour across shallow high passes (their
// dynamics, Grimaud 1992), crowns grown from the remaining tops over the CHM (Dalponte & Coomes
// 2016, §2.3: a cell joins a neighbouring crown when it is high enough relative to that crown's
// top and mean and near it); every vegetation point goes to the crown of its CHM cell, points
// below the crown surface included.
//
// Terrestrial (dense) scans see stems: the points of a slice above the DTM are clustered, and
// clusters that fit upright circles with points under them down to the ground are stems (Liang
// et al. 2012, §2.2); then one multi-source Dijkstra over the whole plot's neighbour graph, from
// all stem bases at once (the multi-root variant of the skeleton's shortest paths, Livny et al.
// 2010, §3), gives every point to the base it reaches most cheaply, an edge costing
// length^graph_beta, its horizontal part times a factor that falls with the stem's radius (a
// thick trunk's crown reaches farther sideways). The graph is built on a voxel-thinned copy of
// the non-ground points with no edge longer than `max_gap`, and every point takes the label of
// its voxel. Pieces of crown the paths do not reach (a sparse top above a gap) join the nearest
// tree when they hang in the air within `attach_gap` of it; the rest (understory apart from the
// trees, clutter beyond a gap, stray returns) stays 0.
// docs/segment.md has the figures and the settings for dense conifer stands.
#pragma once

#include "core/point_cloud.hpp"
#include "segment/terrain.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace treelobes {

enum class ScanMode { Automatic, Airborne, Terrestrial };

// "auto", "als", "tls".
const char* scan_mode_name(ScanMode mode);
// Parses "auto", "als" or "tls"; throws Error(Usage) otherwise.
ScanMode parse_scan_mode(std::string_view text);

struct SegmentOptions {
    ScanMode mode = ScanMode::Automatic;
    float min_tree_height = 2.0f;  // trees whose top is lower are not trees (metres above ground)
    // Automatic choice: terrestrial when the non-ground points are at least this dense over the
    // tile's occupied footprint (points per square metre); airborne otherwise. Airborne surveys
    // give 1-100 per m^2 (dense drone surveys more: pass the mode then), terrestrial plots
    // hundreds to thousands.
    float terrestrial_density = 200.0f;

    // Airborne (canopy height model and crowns).
    float chm_cell = 0.5f;       // CHM cell edge (metres)
    float point_radius = 0.15f;  // each point drawn as a disc of this radius (pit-free CHM)
    // Sparse surveys: the cell is at least cell_per_spacing and the disc radius at least
    // disc_per_spacing times the mean spacing of the vegetation returns (0 = fixed), so that the
    // discs still cover the crowns at 1-2 returns per m^2.
    float cell_per_spacing = 0.75f;
    float disc_per_spacing = 0.7071f;  // 1/sqrt(2): discs of this radius around a square grid of returns cover it
    // The same for a sparse survey (spacing above kSparseSurveyReturnSpacing), whose spacing reads
    // short; only when disc_per_spacing is not 0 (docs/segment.md, "Sparse airborne surveys").
    float sparse_disc_per_spacing = 1.0f;
    // The vegetation returns' mean spacing (metres, at most 10); 0 = estimated from the cloud. A
    // survey cut into tiles gives every tile one value, so that they all draw the same CHM.
    float return_spacing = 0.0f;
    float pit_depth = 1.0f;         // a CHM cell this far below its neighbours' median is a pit, set to that median (metres)
    float chm_smoothing = 0.75f;    // Gaussian sigma of the CHM the tops are searched on (metres; 0 = none)
    float window_base = 2.0f;       // treetop window diameter at 0 m height (metres) ...
    float window_per_metre = 0.1f;  // ... plus this much per metre of height (Popescu & Wynne 2004)
    float max_window = 20.0f;       // cap of the treetop window diameter (metres)
    // A top is part of a higher neighbour's crown when it rises less than
    // max(min_top_prominence, top_prominence_ratio x its height) above the highest pass between
    // them (its dynamics, Grimaud 1992) and that pass is at least merge_pass_ratio x the higher top.
    // The bumps of a broad crown rise higher the taller it is: 2 m up to a 17 m top, 3 m at 25 m,
    // 3.6 m at 30 m. The defaults suit broad crowns (the synthetic species library); dense
    // conifer stands such as lidR's MixedConifer take the conifer preset (StandType below,
    // docs/segment.md).
    float min_top_prominence = 2.0f;  // metres
    float top_prominence_ratio = 0.12f;
    float merge_pass_ratio = 0.5f;
    float seed_ratio = 0.45f;        // a crown cell must be higher than this share of its top (Dalponte 2016: th_seed)
    float crown_ratio = 0.55f;       // ... and higher than this share of the crown's mean height (th_cr)
    float max_crown_radius = 15.0f;  // no crown cell farther than this from its top (metres)

    // Terrestrial (stems and plot-wide shortest paths).
    float stem_slice_low = 1.0f;         // stem slice, metres above ground: from ...
    float stem_slice_high = 2.0f;        // ... to
    float stem_cluster_distance = 0.1f;  // slice points closer than this belong to one cluster (metres)
    // A cluster that holds no stem is split again at this distance (0 = not): a trunk inside a
    // curtain of hanging twigs or under limbs that fill the slice (metres).
    float stem_subcluster_distance = 0.05f;
    float stem_merge_distance = 1.0f;    // stems closer than this are one tree's (multi-stemmed trees; metres)
    // Stems closer than shared_top_stem_distance whose trees' highest voxels lie within
    // shared_top_distance of each other split one crown between them: one tree
    // (a trunk and an arc of its curtain of twigs; 0 = not joined; metres).
    float shared_top_stem_distance = 2.0f;
    float shared_top_distance = 1.0f;
    int min_stem_points = 15;            // smaller slice clusters are not stems
    // A stem continues down to the ground: the points below the slice, within stem_foot_reach
    // radii of its axis (a root flare), hold min_stem_points. A trunk at least
    // buttressed_stem_radius thick may flare wider, into buttresses or a skirt of roots: within
    // buttressed_foot_reach radii; its flare may also fill the slice's lower layers, whose wider
    // circles on its axis then count for it (metres; radii).
    float stem_foot_reach = 1.5f;
    float buttressed_stem_radius = 0.4f;
    float buttressed_foot_reach = 2.5f;
    float min_stem_radius = 0.025f;      // accepted circle radii (metres)
    float max_stem_radius = 0.8f;
    float circle_tolerance = 0.03f;   // circle inlier band (metres)
    float min_circle_inliers = 0.5f;  // share of the cluster's points on the circle
    float min_arc_coverage = 0.2f;    // share of the circle's 10-degree sectors that hold inliers
    float max_stem_lean = 30.0f;      // degrees from vertical between the lower and upper half of a stem's slice points
    // A circle fitted to the whole slice is a stem only when each of the slice's upper three
    // quarters holds its arc over at least this share of the 10-degree sectors the whole slice
    // covers (a drooping limb's band fills only some heights; 0 = not checked).
    float min_quarter_arc_share = 0.1f;
    float stem_layer_height = 0.25f;  // a tapering trunk: circles fitted layer by layer, this thick (metres)
    float trunk_layer_height = 0.1f;  // a thin, leaning trunk under twigs: layers this thick (metres)
    float graph_voxel = 0.1f;         // voxel edge of the thinned cloud the plot graph is built on (metres)
    int graph_neighbours = 10;        // k of the kNN graph
    float graph_beta = 2.0f;          // an edge costs length^beta: > 1 makes jumps across the sparse contact of two crowns dear
    // Paths from a stem of radius r cost (median stem radius / r)^stem_reach_exponent per unit of
    // the horizontal part of their edge costs: thick trunks, which carry wide crowns, reach
    // farther sideways (0 = all stems alike).
    float stem_reach_exponent = 1.0f;
    float max_gap = 1.0f;             // longest graph edge (metres): points beyond wider gaps stay 0 ...
    // ... unless they form a piece hanging in the air (lowest point at least detached_min_height
    // above the ground, at least min_detached_voxels voxels) within attach_gap of a tree's
    // points: a sparse treetop, a tier of a tiered crown; it joins that tree (0 = never).
    float attach_gap = 2.0f;
    float detached_min_height = 2.0f;
    int min_detached_voxels = 3;
    float ground_clearance = 0.3f;    // points lower than this above the DTM stay out of the graph (metres)
};

// Presets of the segmentation for the stand at hand (`treelobes tile --stand`).
// Broadleaf: the defaults above (broad crowns with many maxima: shallow tops merged into higher
// ones, CHM smoothed, crowns up to 15 m from their top; a thick trunk's paths reach farther).
// Conifer: every window maximum is a tree on the unsmoothed CHM and a crown reaches at most
// 3.5 m from its top (narrow, pointed crowns side by side; on lidR's MixedConifer F1 0.90
// against lidR's treeID, 0.29 with the broadleaf preset), and all stems reach alike (narrow
// crowns of one height whatever the diameter: on TreeLS's pine plot a thick pine's paths would
// take the top of a thin neighbour).
enum class StandType { Broadleaf, Conifer };

// Parses "broadleaf" or "conifer"; throws Error(Usage) otherwise.
StandType parse_stand_type(std::string_view text);
// The options with the preset's settings (top merging, CHM smoothing, crown radius, stem reach).
SegmentOptions with_stand_type(SegmentOptions options, StandType stand);

// How far around a crown the airborne segmentation reads points that can change it: the crown
// reaches max_crown_radius from its top, its top is found on the CHM smoothed over 3 sigma
// around it, and its cells are contested by tops as far again: 2 x (max_crown_radius + 3 x
// chm_smoothing), 34.5 m with the broadleaf preset, 7 m with the conifer one. A tile buffer this
// wide gives the crowns of the uncut survey (docs/survey.md: a synthetic survey exact at 32.5 m
// with the broadleaf preset, one tree of 24 differing at 30 m; MixedConifer cut into 45 m tiles
// exact at 7 m with the conifer preset, 4 of 215 trees differing at 3.5 m).
float airborne_reach(const SegmentOptions& options);

struct SegmentedTree {
    std::int32_t id = 0;            // 1.. in the order the trees were found; the treeID of its points
    Eigen::Vector3f base{0, 0, 0};  // local frame, on the DTM: stem centre (terrestrial) or below the top (airborne)
    Eigen::Vector3f top{0, 0, 0};   // local frame: highest point of the tree
    std::size_t points = 0;         // points with this id
    float stem_radius = 0.0f;       // radius of the stem circle that seeded the tree (terrestrial); 0 for airborne
};

struct TreeSegmentation {
    std::vector<std::int32_t> tree_id;  // per point; 0 = no tree (ground, understory, unreachable)
    std::vector<SegmentedTree> trees;   // trees[i].id == i + 1
    ScanMode mode_used = ScanMode::Airborne;
    std::string mode_reason;  // why this mode ("requested", or the density that decided it)
    // Airborne: the CHM's cell and disc radius used, from the options and the vegetation
    // returns' mean spacing (metres; 0 for terrestrial).
    float return_spacing = 0.0f;
    float chm_cell = 0.0f;
    float chm_point_radius = 0.0f;
    // Airborne: the survey's pulses per m^2 (survey_pulse_density), as surveys are ordered and
    // described; 0 for terrestrial.
    float pulse_density = 0.0f;
};

// Mean spacing of the vegetation returns seen from above, which the airborne CHM's cell and discs
// grow with: 1 / sqrt(returns per m^2 over the 2 m cells that hold any). A 2 m cell is missed
// with probability e^-4 at 1 return per m^2, so a sparse survey is not counted denser than it is,
// as it would be over the 1 m cells that happen to be hit. 0 without vegetation.
float vegetation_return_spacing(const PointCloud& cloud, const Terrain& terrain, const SegmentOptions& options);

// A sparse survey: fewer than about 0.5 pulses per m^2, whose vegetation returns read farther
// apart than this by vegetation_return_spacing (0.5 pulses per m^2 read 1.29-1.33 m, 0.35 read
// 1.46-1.51 m). The reading falls short there, as 2 m cells that mostly hold one return cannot
// show more than 2 m (0.1 pulses per m^2 read 1.68-1.80 m for about 3 m), so the CHM's discs take
// the whole spacing (sparse_disc_per_spacing). Crowns still split: on synthetic stands at
// 0.1-0.35 pulses per m^2, mean F1 is 0.58-0.82 (docs/segment.md, "Sparse airborne surveys").
inline constexpr float kSparseSurveyReturnSpacing = 1.45f;

// Pulses per m^2: the first returns (every point when the cloud has no return numbers), ground
// included, over the 10 m cells that hold any point, or over the bounding box when that is
// smaller (a clip of one crown) or when the cells hold fewer than two pulses each (a survey
// sparser than about 0.02 pulses per m^2, whose gaps such cells cannot show). Unlike the return
// spacing it does not saturate in a sparse survey: the returns of one pulse lie in one 2 m cell,
// and the 2 m cells of synthetic stands at 0.025-0.1 pulses per m^2 all read 1.7 m apart; the
// 10 m cells leave out a tile's empty corners. 0 for an empty cloud.
float survey_pulse_density(const PointCloud& cloud);

// Fewer pulses per m^2 than this tell too few crowns apart to be of use: mean F1 0.33-0.43 on
// synthetic stands at 0.025-0.05 pulses per m^2, 0.58-0.62 at 0.1 (docs/segment.md, "Sparse
// airborne surveys").
inline constexpr float kTooSparseForTrees = 0.08f;

// Segments the tile into trees. `terrain` must come from analyse_terrain on the same cloud
// (Error(Internal) when its sizes differ). An empty cloud, or one without points above
// `min_tree_height`, gives no trees and all ids 0. Throws Error(Usage) for invalid options.
TreeSegmentation segment_trees(const PointCloud& cloud, const Terrain& terrain, const SegmentOptions& options);

}  // namespace treelobes
