// One tree from one scan: cleaning, skeleton, stem fit, allometric radii and the per-tree
// summary, as run by `treelobes reconstruct`. Each step is its own header; this file only
// chains them and records what happened.
#pragma once

#include "core/point_cloud.hpp"
#include "core/tree_graph.hpp"
#include "reconstruct/allometry.hpp"
#include "reconstruct/cylinder_axes.hpp"
#include "reconstruct/preprocess.hpp"
#include "reconstruct/recentre.hpp"
#include "reconstruct/skeleton.hpp"
#include "reconstruct/tree_quality.hpp"
#include "reconstruct/trunk.hpp"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace treelobes {

struct ReconstructOptions {
    PreprocessOptions preprocess;
    SkeletonOptions skeleton;
    RecentreOptions recentre;           // thin internodes moved across onto their points (reconstruct/recentre.hpp)
    CylinderAxesOptions cylinder_axes;  // nodes moved onto cylinders fitted to stretches of branch (reconstruct/cylinder_axes.hpp)
    TrunkOptions trunk;
    AllometryOptions allometry;
    QualityOptions quality;
    double root_diameter = 0.0;  // metres; 0 = from the stem fit (else height / 50 when the stem is hidden)
    // Where the stem meets the ground when the scan may not show it (a tile's airborne crowns), in
    // the cloud's local frame: a hidden stem is added from there to the skeleton (add_hidden_trunk).
    std::optional<Eigen::Vector3f> hidden_stem_foot;
    // A warning per cloud that does not look like a tree (summary.quality); a tile reports all of
    // its trees that do not in one line instead.
    bool warn_if_not_a_tree = true;
};

struct TreeSummary {
    std::size_t input_points = 0;
    std::size_t used_points = 0;
    std::size_t duplicates = 0;
    std::size_t outliers = 0;
    bool local_outlier_test = false;  // the local outlier test ran (reconstruct/preprocess.hpp)
    float linear_fraction = -1.0f;    // points with linear neighbourhoods, when measured (-1: not)
    std::size_t ground_points = 0;
    std::size_t detached_points = 0;  // in pieces left out of the skeleton beyond gaps (--max-gap); they keep an internode
    bool ground_removed = false;
    float height = 0.0f;  // metres from the stem foot to the highest point
    bool dbh_fitted = false;
    float dbh = 0.0f;                  // metres (diameter at 1.3 m), when fitted
    float root_diameter = 0.0f;        // d_root of Livny et al. 2011, Eq. 1 (metres)
    std::string root_diameter_source;  // "base fit", "breast height fit", "given", "height / 50"
    float crown_width = 0.0f;          // mean of the two principal horizontal extents (metres)
    float total_length = 0.0f;         // sum of skeleton internode lengths (metres)
    std::size_t branches = 0;          // axes: the trunk plus one per lateral child
    std::size_t internodes = 0;
    std::size_t recentred_nodes = 0;      // nodes moved onto their internode's points
    std::size_t cylinder_axis_nodes = 0;  // nodes moved onto the axis of a fitted cylinder
    std::size_t tips = 0;
    int max_branch_order = 0;
    float spacing = 0.0f;
    float bin_width = 0.0f;
    float internode_length = 0.0f;
    std::size_t graph_components = 0;
    std::size_t bridges = 0;
    float longest_bridge = 0.0f;
    bool stem_visible = false;
    std::size_t hidden_trunk_nodes = 0;  // nodes of the trunk laid from ReconstructOptions::hidden_stem_foot
    QualityReport quality;
    std::vector<std::pair<std::string, double>> seconds;  // wall time per stage
};

struct TreeReconstruction {
    TreeGraph skeleton;             // radii = d(u)/2, origin of the input cloud
    AllometricDiameters diameters;  // d and d' per node
    TrunkFit trunk;
    std::vector<int> point_internode;   // per input point; -1 for points removed as outliers/ground
    std::vector<float> point_geodesic;  // per input point (metres); -1 for removed points
    TreeSummary summary;
};

TreeReconstruction reconstruct_tree(const PointCloud& cloud, const ReconstructOptions& options, const std::string& name = {});

}  // namespace treelobes
