// Synthetic trees with known answers: synth::grow turns a species profile (config/species.yaml)
// and a seed into a tree with its true skeleton, radii and leaves.
//
// The growth model follows Weber & Penn 1995, "Creation and rendering of realistic trees": a trunk and up to three levels of branches, each stem a chain of curved
// segments; first-order branch lengths follow the crown shape (ShapeRatio), deeper ones the
// remaining length of their parent; phyllotaxis by `rotate` (spiral) or alternate sprays, whorls;
// dichotomous forks (`seg_splits`) for decurrent crowns; tropism toward or away from the sky;
// radii by taper and `ratio_power` with a pipe-model split at forks; leaves on the last level.
// docs/species.md describes every parameter. Everything random comes from core/random.hpp, so
// the same (species, seed, options) gives the same tree bit for bit.
#pragma once

#include "config/species_profile.hpp"
#include "core/tree_graph.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace treelobes::synth {

struct GrowOptions {
    double height_m = 0;  // 0: draw the height from the species' variation range
    bool leaves = true;   // false: a leafless (winter) tree
    // Multiplies the number of leaves and divides their area by the same factor, so the total
    // leaf area (and how much a crown occludes) stays: 0.1 gives a tenth of the leaves, each
    // ~3x longer and wider. Tiles scanned from the air use this to fit in memory.
    double leaf_density = 1.0;        // [0.001, 4]
    std::size_t max_leaves = 250000;  // leaf budget per tree: beyond it leaves get fewer and larger
    double max_internode_m = 1.0;     // longer internodes are subdivided (finer labels and meshes)
};

// One leaf blade: a rhombus (broad, leaflet) or a thin strip (needle) from `base` along
// `direction`, facing `normal`.
struct Leaf {
    Eigen::Vector3f base{0, 0, 0};
    Eigen::Vector3f direction{0, 0, 1};
    Eigen::Vector3f normal{1, 0, 0};
    float length = 0.1f;
    float width = 0.05f;
    int internode = 0;  // skeleton node whose internode (parent -> node) carries the leaf
};

struct SyntheticTree {
    std::string species;  // canonical name
    int species_id = 0;
    std::uint64_t seed = 0;
    TreeGraph skeleton;  // root (node 0) at the stem base, local (0,0,0); origin = placement
    // Per node (index = node): the stem level of the internode ending there (0 trunk, 1 first-
    // order branch, ...) and its radius at the parent end (lateral branches start thinner than
    // the node they grow from). Root: level 0, its own radius.
    std::vector<int> node_level;
    std::vector<float> internode_start_radius;
    LeafShape leaf_shape = LeafShape::Broad;
    std::vector<Leaf> leaves;
    float bark_reflectance = 0.45f;
    float leaf_reflectance = 0.55f;
    double age_years = 0;  // drawn with the height; reported in truth tables
};

SyntheticTree grow(const SpeciesProfile& species, std::uint64_t seed, const GrowOptions& options = {});

// Forest-inventory figures of a tree, measured on the geometry (not the drawn targets).
struct TreeMetrics {
    double height_m = 0;          // top of skeleton and leaves above the stem base
    double dbh_m = 0;             // stem diameter at 1.3 m; several stems: sqrt(sum d^2)
    double crown_diameter_m = 0;  // mean of the x and y extents of branches and leaves
    double total_length_m = 0;    // skeleton length
    double leaf_area_m2 = 0;      // one-sided area of all blades
    double lai = 0;               // leaf area / crown projection area (pi d^2 / 4)
    std::size_t internodes = 0;
    std::size_t leaves = 0;
};

TreeMetrics measure(const SyntheticTree& tree);

// Removes every node for which `remove(node)` is true together with all that grows from it (its
// subtree and the leaves on it); the root never goes. `remove` sees the tree as it was: every
// call comes before anything is removed, with the original indices. The kept nodes are
// renumbered in their old order, children keep theirs (main child first). Forest tiles use it
// to let neighbours compete for crown space (synth/tile.hpp).
void prune_subtrees(SyntheticTree& tree, const std::function<bool(int node)>& remove);

// The four (broad, leaflet) or four strip (needle) corners of a leaf, in local coordinates.
std::array<Eigen::Vector3f, 4> leaf_corners(const Leaf& leaf, LeafShape shape);

}  // namespace treelobes::synth
