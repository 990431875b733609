// JointBoost (Torralba et al. 2007, "Sharing visual features for multiclass and multiview
// object detection"; docs/references.md): multiclass boosting whose weak learners are
// regression stumps shared by a subset S of the classes.
//
// Round m fits, by weighted least squares on the one-vs-all targets z_i^c in {+1,-1},
//     h_m(v, c) = a_S  if c in S and v_f > theta
//                 b_S  if c in S and v_f <= theta
//                 k_c  if c not in S
// with a_S, b_S the weighted means of z over the classes of S on each side of the threshold and
// k_c the weighted mean of z^c (so classes outside S do not bias the sharing choice). For every
// feature f and every threshold theta (midpoints of consecutive sorted distinct values, sums by
// prefix/suffix accumulation) the sharing set is chosen by greedy forward selection over all
// classes: start empty, add the class that lowers the error most, until all classes are in; the
// best set on that path (the all-classes set included) is the candidate of (f, theta). The round
// keeps the candidate of least error; ties go to the lower feature index, then the lower
// threshold, then the smaller set. Weights are updated w_i^c <- w_i^c exp(-z_i^c h_m(v_i, c)) and
// renormalised. Training is deterministic and independent of the number of threads.
//
// Classifier output: H(v, c) = sum_m h_m(v, c) estimates half the log-odds of class c against the
// rest (GentleBoost), so the class probabilities are the normalised logistic of 2H / T:
//     p_c = sigma(2 H(v,c) / T) / sum_c' sigma(2 H(v,c') / T),   sigma(t) = 1 / (1 + e^-t).
// Boosting on a few dozen trees per class drives the training margins, and with them H, far
// beyond what held-out trees justify, so with T = 1 nearly every tree looks confident. The
// temperature T is therefore fitted (least held-out log-loss) on the early-stopping validation
// trees, which belong to the training half; the spatial-voting confidence rule h1 > 1.5 h2 is
// applied to these calibrated p_c.
#pragma once

#include "classify/feature_table.hpp"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace treelobes::classify {

struct JointBoostOptions {
    int max_rounds = 800;  // upper bound on the number of stumps
    // Early stopping by stratified, seeded K-fold cross-validation on the training trees: K
    // boosting runs, each on the other K-1 folds, advance round by round together; after every
    // round all training trees are scored out of fold (fewest errors, then lowest mean log-loss
    // of the probabilities above), and training stops `patience` rounds after the best round.
    // The model is then trained on all training trees for K/(K-1) times that number of rounds
    // (more trees take more rounds to fit as closely). Every tree
    // serves for validation once, which matters with ten or twenty trees per species: a single
    // held-out fifth stops at a noisy, far too early round. folds < 2 disables early stopping
    // (max_rounds are used, T = 1).
    int folds = 5;
    int patience = 50;
    // Stop as soon as every out-of-fold tree is right and their mean log-loss (T = 1) is below
    // this: nothing is left to learn out of fold, and more rounds only sharpen margins that the
    // fitted temperature undoes (terrestrial scans reach it after ~100 rounds instead of running
    // to max_rounds on ever smaller log-loss gains). 0 disables it.
    double settled_logloss = 0.01;
    // Fit the temperature T on the out-of-fold scores at the chosen round (false: T = 1).
    bool calibrate = true;
    // The final model: true = the K fold runs cut at the chosen round, averaged (H = mean of
    // their H; their stumps with a, b, k divided by K), which needs no extra boosting run and
    // whose members disagree on the doubtful trees; false = boosting again on all training trees
    // for the chosen number of rounds (one sharper model).
    bool fold_ensemble = true;
    // With the fold ensemble: average the members' probabilities (their mixture: members that
    // disagree leave the tree doubtful, so the confidence rule sends it to the vote) instead of
    // their scores H (one stump list, whose sum can stay confident when members disagree).
    bool average_probabilities = true;
    // Routing by scan kind: when the table has the scan descriptor (kScanDensityFeature) and the
    // training trees' densities fall into two clusters (the widest gap between consecutive log
    // densities is at least a factor route_min_ratio, with route_min_trees trees or more and two
    // or more classes on each side), one sub-model is trained per side and each tree is routed
    // by its density, the threshold being the geometric mean of the gap's ends. Chosen on the
    // training trees only; otherwise one model. The descriptor is never a stump feature.
    bool route_by_scan = true;
    double route_min_ratio = 3.0;
    int route_min_trees = 20;
    // Class imbalance: every tree starts with weight N / (K n_y) (K classes, n_y trees of its
    // class), so that each class weighs the same in total, and out-of-fold errors are counted
    // with the same weights. A balanced training set is unchanged (all weights 1).
    bool balance_classes = true;
    std::uint64_t seed = 1;  // fold assignment
};

struct Stump {
    int feature = 0;
    double threshold = 0;
    // Where a missing value (NaN) goes: chosen in training (each column with missing values is
    // tried with them below and above every threshold), false = below.
    bool missing_above = false;
    bool goes_above(double v) const { return std::isnan(v) ? missing_above : v > threshold; }
    double a = 0;              // value for classes in the set when v_f > threshold
    double b = 0;              // value for classes in the set when v_f <= threshold
    std::vector<int> sharing;  // classes of S, ascending
    std::vector<double> k;     // per class; used for classes outside S
    // Per-class values above/below the threshold (derived from the above; used by evaluation).
    std::vector<double> above, below;
    void finalise(int classes);
};

struct JointBoostModel {
    std::vector<std::string> classes;        // class names, index = class id
    std::vector<std::string> feature_names;  // the columns the stumps index
    std::vector<Stump> stumps;
    double temperature = 1.0;  // T of the probability mapping

    // Routing by scan kind (empty `parts`: a single model). A tree whose feature route_feature is
    // <= route_threshold goes to parts[0] (the sparser scans: airborne), the others to parts[1].
    // Each part is a single model over the same feature_names whose classes are a subset of
    // `classes` (part_class_ids maps them); the classes it lacks get probability 0.
    int route_feature = -1;
    double route_threshold = 0;
    std::vector<JointBoostModel> parts;
    std::vector<std::vector<int>> part_class_ids;
    // Ensemble of members (empty: none): the probabilities are the mean of the members'
    // probabilities, each at this model's temperature; H the mean of their H. `stumps` is then
    // empty.
    std::vector<JointBoostModel> members;

    int class_count() const { return static_cast<int>(classes.size()); }
    bool routed() const { return !parts.empty(); }
    // The part serving a feature vector (routed models only).
    std::size_t part_index(const double* features) const;
    // H(v, c) for one feature vector (length feature_names.size()); routed: the part's H, and
    // -infinity for the classes the part lacks.
    std::vector<double> scores(const double* features) const;
    // Normalised logistic of 2H / T (see above); sums to 1.
    std::vector<double> probabilities(const double* features) const;
};

// Maps scores H to probabilities (the one documented mapping).
std::vector<double> probabilities_from_scores(const std::vector<double>& scores, double temperature = 1.0);

// The temperature in [1/4, 64] (steps of 2^(1/8)) with the least mean log-loss of the true
// classes of held-out trees given their scores H; ties go to the lower temperature.
double fit_temperature(const std::vector<std::vector<double>>& scores, const std::vector<int>& labels);

struct JointBoostReport {
    int rounds = 0;            // boosting rounds of the returned model (fold ensemble: of each member)
    int rounds_tried = 0;      // rounds run before early stopping
    double temperature = 1.0;  // fitted T (1 without calibration; routed: the parts' mean)
    // After each round tried: mean exp(-z H) over trees and classes (the fold runs' mean with
    // cross-validation), and the out-of-fold error rate and mean log-loss (T = 1).
    std::vector<double> training_loss;
    std::vector<double> validation_error;
    std::vector<double> validation_logloss;
    // Routed models: the report of each part (rounds and rounds_tried above are their sums).
    std::vector<JointBoostReport> parts;
};

// Trains on `table` with class ids `labels` (0..classes.size()-1, one per row). Throws
// Error::input when fewer than two classes are present, a value is not finite or labels and
// rows disagree.
JointBoostModel train_jointboost(const FeatureTable& table, const std::vector<int>& labels, const std::vector<std::string>& classes,
                                 const JointBoostOptions& options, JointBoostReport* report = nullptr);

// The boosting rounds themselves, without early stopping (exposed for tests): `rounds` stumps.
JointBoostModel fit_jointboost_rounds(const FeatureTable& table, const std::vector<int>& labels, const std::vector<std::string>& classes,
                                      int rounds, std::vector<double>* training_loss = nullptr, bool balance_classes = false);

// The scan routing train_jointboost would choose for these training trees: the column of the scan
// descriptor and the density threshold, or route_feature = -1 (one model).
std::pair<int, double> choose_scan_routing(const FeatureTable& table, const std::vector<int>& labels, const JointBoostOptions& options);

// Model file: JSON with "format": "treelobes-jointboost", "version": 3, the class and feature
// names, the probability mapping, and either the temperature and stumps (and, for an ensemble
// averaging probabilities, "members": one {stumps} each) of a single model, or "routing"
// (feature name, threshold) with "models": one {scan, classes, temperature, stumps[, members]}
// per scan kind. Written atomically; the reader also takes version 2 (single model) and 1 (no
// temperature: T = 1) files, checks the format, version and every index and name and throws
// Error::input naming the file otherwise.
inline constexpr int kJointBoostModelVersion = 3;
void save_jointboost(const JointBoostModel& model, const std::filesystem::path& path);
JointBoostModel load_jointboost(const std::filesystem::path& path);

}  // namespace treelobes::classify
