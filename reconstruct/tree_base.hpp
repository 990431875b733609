// Where the tree starts: the stem foot. Not simply the lowest point: the bottom of the scan is
// split into connected pieces (stem, hanging branch tips, leftover ground clutter) and the
// biggest piece no wider than a stem can be is taken as the stem; a circle fitted to its foot
// gives the root position.
// When no narrow piece exists (airborne scans: the stem is hidden under the crown) the root is
// placed below the lowest piece and flagged, so callers can fall back on allometry.
#pragma once

#include "geometry/neighbour_graph.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace treelobes {

struct TreeBaseOptions {
    float slab_height = 0.0f;      // metres of the bottom slab searched for the stem (0 = 3 % of the height, 0.2..0.6 m)
    float foot_height = 0.10f;     // metres: stem points this far above its lowest point are the Dijkstra sources
    // A bottom piece wider than max(max_stem_radius, max_stem_radius_per_height x the tree's
    // height) is not a visible stem. Old broadleaves flare beyond 1 m at the foot: the synthetic
    // oak's foot piece is 1.07 m for a 28 m tree, the fig's 1.46 m for a 24 m one
    // (docs/reconstruct.md). A flat bound of 2 m took the underside of small airborne crowns for stems.
    float max_stem_radius = 1.0f;  // metres
    float max_stem_radius_per_height = 1 / 15.0f;
};

struct TreeBase {
    Eigen::Vector3f position{0, 0, 0};  // the root node: stem centre at its lowest point
    std::vector<int> sources;           // points of the stem foot, sorted
    bool stem_visible = false;
    bool circle_fitted = false;     // position from a circle fit (else from the foot centroid)
    float foot_radius = 0.0f;       // fitted foot circle radius (0 when not fitted)
    std::size_t bottom_pieces = 0;  // connected pieces found in the bottom slab
};

TreeBase find_tree_base(std::span<const Eigen::Vector3f> points, const NeighbourGraph& graph, const TreeBaseOptions& options = {});

}  // namespace treelobes
