// The evaluation protocol of Livny et al. 2011, §6.1, and the comparisons a user needs to trust it:
//   - random splits: per species half the trees train, the other half test, `splits` times with
//     different seeds; per-species recognition rate = its test accuracy averaged over the splits,
//     overall = the mean of the per-species rates (the paper's "average recognition rate"); the
//     confusion matrix accumulates every test tree of every split;
//   - site split: each group (tile, site) in turn is the test set and the others train, because
//     random splits let a classifier learn a site's scanner and light rather than the species;
//   - spatial voting on every split whose test trees have positions: voting happens among the
//     test trees of the split (the training trees are not in the scene being classified);
//   - every classifier given (JointBoost, XGBoost) sees exactly the same splits.
#pragma once

#include "classify/feature_table.hpp"
#include "classify/voting.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace treelobes::classify {

// Labelled trees: features, class ids, optional positions and groups.
struct LabelledSet {
    FeatureTable features;
    std::vector<int> labels;                 // per row
    std::vector<std::string> classes;        // class names (sorted)
    std::vector<Eigen::Vector2d> positions;  // per row, or empty
    std::vector<std::string> groups;         // per row ("" = none), or empty
    std::vector<std::string> class_genus;    // per class: its genus ("" = unknown), or empty
};

// Rows and labels joined by id; classes are the sorted distinct species. Throws Error::input
// naming `labels_file` when a row has no label.
LabelledSet make_labelled_set(const FeatureTable& features, const std::vector<TreeLabel>& labels, const std::string& labels_file);

// Planting layouts for sets of single-tree scans that have no positions, so spatial voting can
// be evaluated: `grouped` plants each species in its own street (a row of trees
// `spacing_m` apart, streets 250 m apart: beyond any voting radius up to 125 m), as in towns;
// otherwise the trees fill a square grid of the same spacing in a seeded random order (a mixed
// planting). Deterministic for (labels, seed).
std::vector<Eigen::Vector2d> planting_layout(const std::vector<int>& labels, int classes, bool grouped, double spacing_m,
                                             std::uint64_t seed);

struct ClassifierRun {
    std::vector<std::vector<double>> probabilities;  // per test row
    double train_seconds = 0, predict_seconds = 0;
    // Process CPU time of the training and prediction over all threads (set by the evaluation):
    // unlike the wall times it does not grow when other jobs share the cores.
    double cpu_seconds = 0;
    int rounds = 0;
};
// Trains on (train, labels) with `classes` classes and predicts `test`; `seed` varies per split.
using Classifier = std::function<ClassifierRun(const FeatureTable& train, const std::vector<int>& labels, int classes,
                                               const FeatureTable& test, std::uint64_t seed)>;

struct NamedClassifier {
    std::string name;
    Classifier run;
};

struct EvaluationOptions {
    int splits = 100;
    double train_fraction = 0.5;
    std::uint64_t seed = 1;
    VotingOptions voting;
    bool site_split = true;  // leave-one-group-out when the set has two or more groups
    // ... and when every group shares species with the others: at least this share of each
    // group's trees belongs to species that the other groups also have (otherwise a group's test
    // trees are of species never trained, and the split can only report 0 %).
    double site_split_min_shared = 0.5;
};

struct Scores {
    std::vector<double> species_rate;  // per class: mean over splits of its test accuracy
    std::vector<int> species_trees;    // per class: trees in the set
    std::vector<int> species_train;    // per class: training trees per split
    double average_rate = 0;           // mean of species_rate (paper's figure)
    double tree_accuracy = 0;          // correct / all test predictions
    // From the confusion matrix (all test trees of all splits): macro-F1 (mean over the species of
    // 2PR / (P + R)) and Cohen's kappa ((p_o - p_e) / (1 - p_e), agreement beyond chance).
    double macro_f1 = 0, kappa = 0;
    // The same predictions at genus level (species mapped to their genus; sets with genera only):
    // tree accuracy, mean per-genus recognition rate, macro-F1 and kappa.
    bool genus_level = false;
    std::vector<std::string> genera;
    double genus_tree_accuracy = 0, genus_average_rate = 0, genus_macro_f1 = 0, genus_kappa = 0;
    std::vector<std::vector<double>> confusion;  // [true][predicted] counts over all splits
    // Confidence rule h1 > factor h2 on the classifier's own predictions.
    double confident_fraction = 0, confident_accuracy = 0, unconfident_accuracy = 0;
    bool voted = false;  // positions were available
    double voted_average_rate = 0, voted_tree_accuracy = 0;
    std::vector<double> voted_species_rate;
    double train_seconds = 0, predict_seconds = 0;  // totals over the splits
    double cpu_seconds = 0;                         // total CPU time of training + prediction
    double mean_rounds = 0;
    int experiments = 0;  // splits (or groups) evaluated
    // Per row of the set: [row][predicted class] = how often it was predicted so when tested.
    std::vector<std::vector<int>> row_predictions;
};

struct ClassifierReport {
    std::string name;
    Scores random_splits;
    Scores site_split;  // experiments == 0 when not run
};

struct EvaluationReport {
    std::vector<std::string> classes;
    std::vector<std::string> tree_ids;     // per row of the set
    std::vector<int> tree_labels;          // per row
    std::vector<std::string> tree_groups;  // per row, or empty
    std::vector<ClassifierReport> classifiers;
    std::vector<std::string> site_groups;
    std::string site_split_note;         // why the site split did not run ("" when it ran or was not asked)
    std::string mode = "random_splits";  // or "train_test": one experiment, a training set against a test set
    double seconds = 0;
};

// Throws Error::input when a species has fewer than 2 trees (it cannot be both trained and tested).
EvaluationReport evaluate(const LabelledSet& set, const std::vector<NamedClassifier>& classifiers, const EvaluationOptions& options);

// One experiment: train on the rows `train`, test on the rows `test` (e.g. two dataset folders).
// Reported as random_splits with one experiment; species of the test set that the training set
// lacks can only be wrong (the report lists them).
EvaluationReport evaluate_train_test(const LabelledSet& set, const std::vector<NamedClassifier>& classifiers,
                                     const std::vector<std::size_t>& train, const std::vector<std::size_t>& test,
                                     const EvaluationOptions& options);

// Genus of a scientific name: its first word ("Quercus rubra L." -> "Quercus"); "" for "".
std::string genus_of(const std::string& scientific_name);

// Writes report/: summary.json (with the random-split accuracy per group, e.g. per scanner, when
// the set has groups), per_species.csv, confusion_<name>.csv and .png (row-normalised percentages
// as Livny et al. 2011, Fig. 7), per_tree_<name>.csv (how often each tree was tested, right, and its most
// frequent wrong species), site_confusion_<name>.csv when a site split ran, report.md.
// `extra_json` holds the summary.json fields the caller adds (the command and its options).
void write_report(const EvaluationReport& report, const std::string& directory, const std::string& extra_json = "{}");

// The human summary printed by `classify evaluate`.
std::string report_summary(const EvaluationReport& report);

}  // namespace treelobes::classify
