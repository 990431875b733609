// Features of many trees: one tree per file, or many per file split by a per-point tree-id
// attribute (synth tiles, lidR-segmented plots: `treeID`). A tree that fails (too few points,
// unreadable file) is reported and skipped; the others go on (DESIGN.md: one failure never
// stops a batch).
#pragma once

#include "classify/feature_table.hpp"
#include "classify/features.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::classify {

struct BatchInput {
    std::filesystem::path file;
    std::string id;              // row id; with a tree attribute each tree is "<id>/<tree id>"
    std::string tree_attribute;  // "" = the whole file is one tree
};

struct BatchFailure {
    std::string id;
    std::string reason;
};

struct FeatureBatch {
    FeatureTable table;                      // rows in input order (trees by ascending id)
    std::vector<Eigen::Vector2d> positions;  // per row: mean x, y of the tree's points (original coordinates)
    std::vector<CrownCounts> crowns;         // per row: what the crown extraction removed
    std::vector<BatchFailure> failures;
    std::size_t points = 0;
    double seconds = 0;
    double feature_seconds = 0;  // wall time summed over trees (without reading files); trees run in
                                 // parallel, so on a loaded machine this exceeds the CPU time
    double cpu_seconds = 0;      // process CPU time of the whole batch, all threads (reading included)
};

// Totals of the crown extraction over the rows, as JSON text ({"ground": ..., ...}) for summaries.
std::string crown_counts_json(const std::vector<CrownCounts>& crowns);
// Per row: id,points,noise,ground,high_outliers,understorey,ground_found,shape_features.
std::string crown_counts_csv(const FeatureBatch& batch);

FeatureBatch compute_feature_batch(const std::vector<BatchInput>& inputs, const FeatureOptions& options);

// Trees of a cloud by the values of an integer attribute (0 and the attribute's no-data value
// mean "no tree"); ascending ids. Throws Error::input naming `file` when the attribute is absent.
std::vector<std::pair<long long, PointCloud>> split_trees(const PointCloud& cloud, const std::string& attribute, const std::string& file);

}  // namespace treelobes::classify
