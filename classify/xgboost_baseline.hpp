// The baseline classifier: XGBoost (Chen & Guestrin 2016; Debian libxgboost-dev, C API, objective multi:softprob) on
// the same features and splits as JointBoost, with the same early stopping (the same held-out
// trees, the same criterion: fewest errors, then lowest mean log-loss; then a refit on all
// training trees for the chosen number of rounds).
#pragma once

#include "classify/feature_table.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace treelobes::classify {

struct XGBoostOptions {
    int max_rounds = 300;
    double eta = 0.1;
    int max_depth = 4;
    double validation_fraction = 0.2;  // as JointBoostOptions
    int patience = 30;
    std::uint64_t seed = 1;
    int threads = 0;              // 0 = as many as TBB may use
    bool balance_classes = true;  // tree weights N / (K n_y), as JointBoostOptions
};

struct XGBoostRun {
    std::vector<std::vector<double>> probabilities;  // per test row, per class
    int rounds = 0;
    double train_seconds = 0, predict_seconds = 0;
};

// Trains on (train, labels) and predicts `test` (columns must match). Throws Error(Internal)
// with XGBoost's message when the library fails.
XGBoostRun xgboost_train_predict(const FeatureTable& train, const std::vector<int>& labels, int classes, const FeatureTable& test,
                                 const XGBoostOptions& options);

// "xgboost 1.7.4" (the library linked in).
std::string xgboost_version();

}  // namespace treelobes::classify
