// Shape features of one tree for species classification (Livny et al. 2011, §6.1): more than 200 numbers
// from the points and from a first skeleton reconstruction. docs/features.md lists every feature
// with its unit and how it is computed; `feature_catalogue()` is the same list in code, and the
// extractor checks each value it emits against it.
//
// Invariance: every feature is computed in the tree's own frame (origin at the stem foot, z up,
// horizontal directions relative to the crown's principal axes), so it does not change when the
// tree is moved or turned about the vertical. Density: the points are first reduced to one per
// voxel of a size proportional to the tree height, and features are distributions (fractions,
// quantiles, moments, angles) of those voxel points, so a thinned scan gives nearly the same
// vector. Only the trunk diameter and the point-count variation read the raw points; the scan
// group's point density is the one feature that follows the density on purpose (routing only).
#pragma once

#include "classify/crown.hpp"
#include "core/point_cloud.hpp"

#include <string>
#include <vector>

namespace treelobes::classify {

struct FeatureOptions {
    // Voxel size = height x voxel_fraction, clamped to [min_voxel, max_voxel] metres.
    double voxel_fraction = 0.01;
    double min_voxel = 0.03;
    double max_voxel = 0.25;
    int normal_neighbours = 12;           // k of the local PCA (normals, curvature, eigen-features)
    bool skeleton = true;                 // false: the skeleton group is filled with zeros (faster)
    std::size_t max_raw_points = 400000;  // raw points read for the trunk and count features (evenly thinned above)
    // Crowns with fewer points (after the crown extraction) get only the airborne group and the
    // scan density; the shape groups need a frame, normals and a skeleton and are missing (NaN).
    std::size_t min_shape_points = 50;
    CrownOptions crown;  // ground, understorey, noise and outliers removed first
};

struct FeatureInfo {
    std::string name;
    std::string group;        // shape, vertical, radial, horizontal, normals, structure, hull, skeleton, envelope, scan, airborne
    std::string unit;         // "m", "m^2", "deg", "1" (dimensionless), "count", "1/m", "1/m^2"
    std::string description;  // how it is computed
};

// Every feature, in the order of the vectors below.
const std::vector<FeatureInfo>& feature_catalogue();
std::vector<std::string> feature_names();

// Time spent per group (seconds) for the benchmark.
struct FeatureTimings {
    double prepare = 0, points = 0, normals = 0, hull = 0, skeleton = 0;
};

// The features of one tree's points (z up, metres). The crown is extracted first (classify/crown.hpp;
// `crown` receives what was removed). Every tree with at least one point gets a vector: features
// that cannot be computed are NaN (missing). Throws Error::input naming `name` when the cloud is
// empty, or has enough points for the shape groups but is too flat to be a tree.
std::vector<double> compute_features(const PointCloud& cloud, const FeatureOptions& options = {}, const std::string& name = {},
                                     FeatureTimings* timings = nullptr, CrownCounts* crown = nullptr);

// The scan group's feature: input points per m^2 of crown cover. It tells the scan kind (airborne
// or terrestrial), changes with the point density by design, and is never a JointBoost stump
// feature (it routes trees to per-scan-kind models); the XGBoost baseline sees it like any column.
inline constexpr const char* kScanDensityFeature = "scan_point_density";
// True for features that describe the scan rather than the tree (JointBoost routes by them and
// never splits on them).
bool is_scan_descriptor(const std::string& feature_name);

// docs/features.md as generated from the catalogue (a test keeps the committed file in sync).
std::string features_markdown();

}  // namespace treelobes::classify
