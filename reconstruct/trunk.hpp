// Stem measurements along the skeleton's main axis: circles fitted to thin slices of the stem
// (points assigned to trunk internodes, projected on the plane across the local stem
// direction, so leaning stems and low branches do not bias them). Gives the DBH at 1.3 m and
// the diameter at the tree base (d_root of Livny et al. 2011, Eq. 1).
#pragma once

#include "core/tree_graph.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace treelobes {

struct TrunkOptions {
    float breast_height = 1.3f;       // metres above the stem foot
    float slice_thickness = 0.10f;    // metres
    float base_low = 0.1f;            // metres: base diameter from slices between base_low ...
    float base_high = 1.5f;           // ... and base_high above the foot
    float max_radius = 1.5f;          // metres
    float min_coverage = 0.25f;       // fraction of the circle that must hold points for a trusted fit
    float circle_tolerance = 0.015f;  // metres: RANSAC inlier band of the circle fit
};

struct StemSlice {
    float height = 0.0f;  // above the foot (metres)
    Eigen::Vector3f centre{0, 0, 0};
    float radius = 0.0f;
    float rms = 0.0f;
    float coverage = 0.0f;
    std::size_t points = 0;
    bool good = false;
};

struct TrunkFit {
    std::vector<StemSlice> slices;  // every 0.1 m from base_low up to breast height + 0.2 m
    bool dbh_fitted = false;
    float dbh = 0.0f;  // diameter at breast height (metres)
    bool foot_fitted = false;
    Eigen::Vector3f foot_centre{0, 0, 0};  // stem axis at the foot height, from the lowest good slices
    bool base_fitted = false;
    float base_diameter = 0.0f;  // median diameter of the good slices between base_low and base_high
};

// `point_internode` maps each point to its internode (the node at its upper end), as produced
// by reconstruct_skeleton. Slices without a trusted circle are reported with good = false.
TrunkFit fit_trunk(std::span<const Eigen::Vector3f> points, const std::vector<int>& point_internode, const TreeGraph& tree,
                   const TrunkOptions& options = {});

// Moves the main axis's nodes between the foot and the highest good slice onto the stem axis the
// slices give (their centres, interpolated by height; below the lowest one, the line from the
// fitted foot). The skeleton's first nodes come from geodesic bins around the root, which cut
// the stem obliquely and fall apart into pieces, so the axis used to hook inside the stem (0.2 m
// off a 0.21 m birch trunk's centre at 0.25 m, the rebuild bench's trees). Returns the nodes moved.
std::size_t align_trunk_base(TreeGraph& tree, const TrunkFit& fit);

// Airborne crowns show no stem: the skeleton starts at the crown's lowest points, metres above
// the ground. Given the stem's foot (a tile's segmentation places it on the ground), lays a
// straight trunk of internodes at most `internode_length` long from the foot to the skeleton's
// root, so the model stands on the ground and its stem counts in the woody volume. The foot
// becomes node 0 and the old nodes keep their order after the trunk's (pre-order holds): old
// node v is node v + the returned count afterwards. Returns 0 (and changes nothing) when the
// root is not more than one internode above the foot.
std::size_t add_hidden_trunk(TreeGraph& tree, const Eigen::Vector3f& foot, float internode_length);

}  // namespace treelobes
