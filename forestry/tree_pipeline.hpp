// Every tree of a segmented tile through the single-tree stages: skeleton and radii
// (reconstruct/reconstruct_tree.hpp), lobes and the .tlobe bytes (lobes/), the DBF6 tree file
// (encode/), the forestry measures (forestry/measures.hpp) and, with a model, species
// probabilities (classify/). Each tree runs in its own error boundary: a tree that fails is
// reported with its reason and the others go on. A tree with fewer points than a model needs
// (`min_points`: the top of a small tree seen through the canopy) is measured but not modelled,
// so an inventory still lists it. Trees run in parallel (TBB); every tree's
// results depend only on its own points and the options, so outputs are deterministic.
#pragma once

#include "classify/features.hpp"
#include "classify/voting.hpp"
#include "core/error.hpp"
#include "core/point_cloud.hpp"
#include "core/tree_graph.hpp"
#include "core/triangle_mesh.hpp"
#include "encode/tree_file.hpp"
#include "forestry/measures.hpp"
#include "lobes/lobe_tree.hpp"
#include "lobes/tlobe_io.hpp"
#include "geometry/branch_mesh.hpp"
#include "reconstruct/reconstruct_tree.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace treelobes::classify {
struct JointBoostModel;
}

namespace treelobes::forestry {

struct TreeInput {
    int id = 0;                              // the tree's id in the tile (> 0)
    PointCloud points;                       // its points: positions in the tile's local frame, the tile's origin
    std::vector<float> height_above_ground;  // per point, metres
    Eigen::Vector3d base{0, 0, 0};           // stem base from the segmentation, local frame
    // Whether `base` was found at the stem (a terrestrial stem circle, the lowest points of a scan
    // that reaches the ground) or only placed under the treetop (airborne): the crown's centre is
    // then the better estimate of where the stem stands.
    bool base_at_stem = true;
};

struct TreePipelineOptions {
    ReconstructOptions reconstruct;
    lobes::LobeOptions lobes;
    lobes::TlobeOptions tlobe;
    encode::TreeFileOptions dbf6;
    BranchMeshOptions mesh;
    DbhOptions dbh;
    CrownOptions crown;
    std::size_t min_points = 50;                       // smaller trees are measured, not modelled
    const classify::JointBoostModel* model = nullptr;  // species probabilities when set
    classify::FeatureOptions features;
};

struct TreeMeasures {
    int id = 0;
    Eigen::Vector3d position{0, 0, 0};  // stem base, local frame (x, y of the DBH circle when fitted)
    double height = 0;                  // metres: highest point above the ground at the stem (docs/tile.md)
    DbhMeasure dbh;
    CrownMeasure crown;
    std::optional<double> woody_volume;  // cubic metres, from the skeleton's cylinders (none without a model)
    std::size_t points = 0;
    std::vector<double> species_probabilities;  // per model class; empty without a model
    // Modelled trees: whether the points look like a building's rather than a tree's (more than a
    // share of them on wide planes: roofs, walls; reconstruct/tree_quality.hpp). Unset for trees
    // measured only.
    std::optional<bool> not_a_tree;
};

// The per-tree files' contents, handed to the caller once and then dropped.
struct TreeProducts {
    TreeGraph skeleton;  // tile origin, radii from the allometry
    TriangleMesh branches;
    std::string tlobe;               // .tlobe bytes
    std::vector<std::uint8_t> dbf6;  // .dbf6 bytes
    std::size_t lobes = 0;
};

struct TreeOutcome {
    int id = 0;
    bool ok = false;        // measured (and modelled unless too small)
    bool modelled = false;  // skeleton, lobes and DBF6 made (ok and at least min_points points)
    std::string failure;    // the reason when !ok
    ExitCode failure_code = ExitCode::Ok;
    TreeMeasures measures;                                // valid when ok
    TreeGraph skeleton;                                   // kept for the tile's .forest
    std::vector<std::pair<std::string, double>> seconds;  // per stage
};

// One tree; throws Error when a stage fails (process_trees catches it).
TreeOutcome process_tree(const TreeInput& tree, const TreePipelineOptions& options, TreeProducts& products);

// All trees, in parallel. `done` is called once per tree as soon as it finishes (from worker
// threads, one call at a time), with the outcome and, for trees that were modelled, their products.
// Outcomes are returned in the order of `trees`.
using TreeDone = std::function<void(const TreeOutcome&, const TreeProducts*)>;
std::vector<TreeOutcome> process_trees(std::span<const TreeInput> trees, const TreePipelineOptions& options, const TreeDone& done);

// Spatial voting of species across the tile (Livny et al. 2011 §6.1 as in classify/voting.hpp)
// over the trees that have probabilities. Returns per outcome the voted class (-1: none).
std::vector<int> vote_species(const std::vector<TreeOutcome>& outcomes, const classify::VotingOptions& options);

}  // namespace treelobes::forestry
