// Skeleton accuracy against a reference (`treelobes eval skeleton`, issue item 7).
//
// References come in three kinds:
//   skeleton  skeleton PLY (vertex x y z [radius], edge vertex1 vertex2); any number of
//             connected pieces (peers' skeletons are forests), vertex 0 taken as the root;
//   treeqsm   a QSM (core/qsm_io.hpp): TreeQSM cylinder table (no header: radius, length,
//             start x y z, axis x y z, parent, extension, added, unmodified radius, branch,
//             branch order, position in branch) or SimpleForest/rTwig CSV (metres);
//   points    a dense list of skeleton points "x y z" (WoodSKE), commas or whitespace.
// Both sides are sampled every `sample_step` along their segments (points are used as they are)
// and distances are measured from each sample to the nearest segment (or point) of the other.
// Trunk radius: both stems' radii at breast height, `breast_height` above the reference stem's
// base (where DBH is measured), interpolated along each stem; the radius at the stem base would
// compare a root flare (synthetic palms, TreeQSM's first cylinder) with a fitted trunk.
// Branch detection (reference trees with radii): the axes of a tree are root-to-tip along main
// children plus fork-to-tip for every lateral child. A reference axis is a scored branch when it
// leaves its fork thicker than `min_branch_diameter`, and it is detected when at least
// `min_matched_fraction` of its samples on segments still thicker than that lie within
// max(match_distance, reference radius) of the skeleton (the thin twig a branch tapers into is
// not part of "a branch thicker than 2 cm"). Precision: a skeleton axis of at least
// `min_branch_length` is correct when that fraction of all its samples lies within
// max(match_distance, radius of the nearest reference segment) of the reference.
#pragma once

#include "core/tree_graph.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace treelobes {

// A point of a main stem, from its base up, with the stem's radius there.
struct StemSample {
    Eigen::Vector3d position;
    double radius = 0;
};

// A skeleton as a general graph (possibly several pieces), in double global coordinates.
struct SkeletonGraph {
    std::string kind;  // "skeleton", "treeqsm", "points"
    std::vector<Eigen::Vector3d> vertices;
    std::vector<float> radius;  // per vertex (0 when unknown)
    std::vector<std::pair<int, int>> edges;
    std::vector<std::pair<int, int>> links;  // connections without length (TreeQSM child -> parent cylinder)
    // The main stem with radii (empty without radii): a skeleton tree's root-to-tip axis along main
    // children, another skeleton's vertex 0 alone, a QSM's stem (order 0) cylinders.
    std::vector<StemSample> stem;
    std::optional<TreeGraph> tree;   // when the edges form one tree rooted at vertex 0
    std::size_t components() const;  // connected pieces (isolated vertices count, except for point lists)
    double total_length() const;
};

// The root-to-tip axis of a tree along main children, in global coordinates, with radii.
std::vector<StemSample> main_stem(const TreeGraph& tree);

// kind: "auto" (by extension and column count), "skeleton", "treeqsm" or "points".
// Throws Error(InvalidInput) naming the file for anything malformed, Error(Usage) for a bad kind.
SkeletonGraph read_skeleton_graph(const std::filesystem::path& path, const std::string& kind = "auto");

struct DistanceStats {
    std::size_t samples = 0;
    double mean = 0, median = 0, p95 = 0, max = 0;
};

struct BranchDetection {
    std::size_t reference_branches = 0;  // reference axes thicker than min_branch_diameter
    std::size_t detected = 0;
    std::size_t skeleton_branches = 0;  // our axes at least min_branch_length long
    std::size_t correct = 0;
    double recall = 0, precision = 0;
};

struct SkeletonComparison {
    DistanceStats to_reference;    // skeleton samples -> reference
    DistanceStats from_reference;  // reference samples -> skeleton
    double length = 0;
    std::optional<double> reference_length;  // not for point lists
    std::optional<double> length_ratio;      // length / reference_length
    std::optional<double> touched_reference_length;  // compare_with_visible_part: every internode the scan touched
    // At breast height (EvalOptions::breast_height above the reference stem's base); error relative to the reference.
    std::optional<double> trunk_radius, reference_trunk_radius, trunk_radius_error;
    std::size_t components = 0, reference_components = 0;
    std::optional<BranchDetection> branches;  // when the reference is a tree with radii
    // Skeleton samples (global coordinates) and their distance to the reference, to see where
    // a skeleton is wrong (`eval skeleton --samples-out`).
    std::vector<Eigen::Vector3d> sample_positions;
    std::vector<float> sample_distances;
};

struct EvalOptions {
    double sample_step = 0.01;          // metres between samples along segments
    double min_branch_diameter = 0.02;  // reference branches thinner than this are not scored
    double match_distance = 0.05;       // metres: a sample within max(this, the branch radius) is matched
    double min_matched_fraction = 0.5;  // of a branch's (thick part's) length, to count it detected / correct
    double min_branch_length = 0.1;     // metres: shorter axes of the skeleton are not scored for precision
    double breast_height = 1.3;         // metres above the reference stem's base where trunk radii are compared
};

SkeletonComparison compare_skeletons(const SkeletonGraph& skeleton, const SkeletonGraph& reference, const EvalOptions& options = {});

}  // namespace treelobes
