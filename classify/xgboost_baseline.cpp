#include "classify/xgboost_baseline.hpp"

#include "classify/splits.hpp"
#include "core/error.hpp"

#include <tbb/global_control.h>
#include <xgboost/c_api.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>

namespace treelobes::classify {

namespace {

void check(int status, const char* what) {
    if (status != 0) throw Error(ExitCode::Internal, std::string("XGBoost ") + what + ": " + XGBGetLastError());
}

struct Matrix {
    DMatrixHandle handle = nullptr;
    // Missing features (NaN) are XGBoost's missing values: each split learns their default
    // direction. With `balance`, each tree weighs N / (K n_y), as in JointBoost.
    Matrix(const FeatureTable& t, const std::vector<std::size_t>& rows, const std::vector<int>* labels, bool balance = false) {
        std::vector<float> data;
        data.reserve(rows.size() * t.cols());
        for (auto r : rows)
            for (std::size_t c = 0; c < t.cols(); ++c) data.push_back(static_cast<float>(t.at(r, c)));
        check(XGDMatrixCreateFromMat(data.data(), rows.size(), t.cols(), std::numeric_limits<float>::quiet_NaN(), &handle), "matrix");
        if (labels) {
            std::vector<float> y;
            for (auto r : rows) y.push_back(static_cast<float>((*labels)[r]));
            check(XGDMatrixSetFloatInfo(handle, "label", y.data(), y.size()), "labels");
            if (balance) {
                std::map<int, double> count;
                for (auto r : rows) ++count[(*labels)[r]];
                std::vector<float> w;
                for (auto r : rows)
                    w.push_back(static_cast<float>(static_cast<double>(rows.size()) / (count.size() * count[(*labels)[r]])));
                check(XGDMatrixSetFloatInfo(handle, "weight", w.data(), w.size()), "weights");
            }
        }
    }
    ~Matrix() { XGDMatrixFree(handle); }
    Matrix(const Matrix&) = delete;
    Matrix& operator=(const Matrix&) = delete;
};

struct Booster {
    BoosterHandle handle = nullptr;
    Booster(const Matrix& train, int classes, const XGBoostOptions& o) {
        check(XGBoosterCreate(&train.handle, 1, &handle), "booster");
        const int threads = o.threads > 0
                                    ? o.threads
                                    : static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
        // XGBoost parses "seed" as a signed integer: the split seeds are 64-bit, so keep 31 bits.
        const std::pair<const char*, std::string> params[] = {
                {"objective", "multi:softprob"},
                {"num_class", std::to_string(classes)},
                {"eta", std::to_string(o.eta)},
                {"max_depth", std::to_string(o.max_depth)},
                {"seed", std::to_string(o.seed & 0x7fffffffu)},
                {"nthread", std::to_string(threads)},
                {"tree_method", "hist"},
                {"verbosity", "0"},
        };
        for (const auto& [key, value] : params) check(XGBoosterSetParam(handle, key, value.c_str()), key);
    }
    ~Booster() { XGBoosterFree(handle); }
    Booster(const Booster&) = delete;
    Booster& operator=(const Booster&) = delete;

    void boost(const Matrix& train, int iteration) { check(XGBoosterUpdateOneIter(handle, iteration, train.handle), "update"); }
    std::vector<std::vector<double>> predict(const Matrix& m, std::size_t rows, int classes) const {
        bst_ulong length = 0;
        const float* out = nullptr;
        check(XGBoosterPredict(handle, m.handle, 0, 0, 0, &length, &out), "predict");
        if (length != rows * static_cast<std::size_t>(classes)) throw Error(ExitCode::Internal, "XGBoost predict: unexpected output size");
        std::vector<std::vector<double>> p(rows, std::vector<double>(classes));
        for (std::size_t r = 0; r < rows; ++r)
            for (int c = 0; c < classes; ++c) p[r][c] = out[r * classes + c];
        return p;
    }
};

std::vector<std::size_t> all_rows(std::size_t n) {
    std::vector<std::size_t> rows(n);
    for (std::size_t i = 0; i < n; ++i) rows[i] = i;
    return rows;
}

// Rounds chosen on the held-out trees: the round with fewest errors, then lowest log-loss.
int choose_rounds(const FeatureTable& train, const std::vector<int>& labels, int classes, const XGBoostOptions& o) {
    std::vector<std::size_t> validation, fit;
    stratified_split(labels, classes, o.validation_fraction, o.seed, false, validation, fit);
    if (validation.empty() || o.validation_fraction <= 0) return o.max_rounds;
    const Matrix fit_matrix(train, fit, &labels, o.balance_classes);
    const Matrix validation_matrix(train, validation, nullptr);
    Booster booster(fit_matrix, classes, o);
    std::pair<int, double> best{std::numeric_limits<int>::max(), std::numeric_limits<double>::infinity()};
    int best_rounds = 1;
    for (int m = 0; m < o.max_rounds; ++m) {
        booster.boost(fit_matrix, m);
        const auto p = booster.predict(validation_matrix, validation.size(), classes);
        int errors = 0;
        double logloss = 0;
        for (std::size_t i = 0; i < validation.size(); ++i) {
            const int truth = labels[validation[i]];
            errors += static_cast<int>(std::max_element(p[i].begin(), p[i].end()) - p[i].begin()) != truth;
            logloss -= std::log(std::max(p[i][truth], 1e-15));
        }
        const std::pair<int, double> score{errors, logloss / static_cast<double>(validation.size())};
        if (score < best) best = score, best_rounds = m + 1;
        if (o.patience > 0 && m + 1 - best_rounds >= o.patience) break;
    }
    return best_rounds;
}

}  // namespace

XGBoostRun xgboost_train_predict(const FeatureTable& train, const std::vector<int>& labels, int classes, const FeatureTable& test,
                                 const XGBoostOptions& options) {
    if (train.cols() != test.cols()) throw Error(ExitCode::Internal, "XGBoost: train and test tables differ in columns");
    XGBoostRun run;
    const auto start = std::chrono::steady_clock::now();
    run.rounds = choose_rounds(train, labels, classes, options);
    const Matrix train_matrix(train, all_rows(train.rows()), &labels, options.balance_classes);
    Booster booster(train_matrix, classes, options);
    for (int m = 0; m < run.rounds; ++m) booster.boost(train_matrix, m);
    const auto trained = std::chrono::steady_clock::now();
    run.train_seconds = std::chrono::duration<double>(trained - start).count();
    const Matrix test_matrix(test, all_rows(test.rows()), nullptr);
    run.probabilities = booster.predict(test_matrix, test.rows(), classes);
    run.predict_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - trained).count();
    return run;
}

std::string xgboost_version() {
    int major = 0, minor = 0, patch = 0;
    XGBoostVersion(&major, &minor, &patch);
    return "xgboost " + std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch);
}

}  // namespace treelobes::classify
