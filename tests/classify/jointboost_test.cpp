// JointBoost on synthetic feature tables with known structure, against a naive reference
// implementation of the same rounds, and model files.
#include "classify/features.hpp"
#include "classify/jointboost.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/random.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <span>
#include <tuple>

using namespace treelobes;
using namespace treelobes::classify;
using treelobes::test::TempDir;

namespace {

std::vector<std::string> class_names(int n) {
    std::vector<std::string> names;
    for (int c = 0; c < n; ++c) names.push_back("class" + std::to_string(c));
    return names;
}

FeatureTable empty_table(int features) {
    FeatureTable t;
    for (int f = 0; f < features; ++f) t.feature_names.push_back(test::numbered("f", static_cast<std::size_t>(f)));
    return t;
}

// `per_class` samples of each class; class c has mean +-5 on feature c % dims (sign by c / dims)
// and unit noise elsewhere, plus one pure-noise feature.
void gaussian_clusters(int classes, int dims, int per_class, std::uint64_t seed, FeatureTable& table, std::vector<int>& y) {
    Rng rng(seed);
    table = empty_table(dims + 1);
    std::vector<double> row(dims + 1);
    for (int i = 0; i < per_class; ++i)
        for (int c = 0; c < classes; ++c) {
            for (int d = 0; d <= dims; ++d) row[d] = rng.normal();
            row[c % dims] += (c / dims) % 2 == 0 ? 5.0 : -5.0;
            table.add_row(test::numbered("t", static_cast<std::size_t>(table.rows())), row);
            y.push_back(c);
        }
}

// Every stump of a model: its own, its ensemble members' and its routed parts'.
std::vector<Stump> all_stumps(const JointBoostModel& model) {
    std::vector<Stump> out = model.stumps;
    for (const auto* list : {&model.members, &model.parts})
        for (const auto& sub : *list) {
            const auto more = all_stumps(sub);
            out.insert(out.end(), more.begin(), more.end());
        }
    return out;
}

double accuracy(const JointBoostModel& model, const FeatureTable& table, const std::vector<int>& y) {
    int correct = 0;
    for (std::size_t r = 0; r < table.rows(); ++r) {
        const auto p = model.probabilities(table.row(r));
        correct += std::max_element(p.begin(), p.end()) - p.begin() == y[r];
    }
    return static_cast<double>(correct) / static_cast<double>(table.rows());
}

// ---- naive reference: the rounds of JointBoost written as directly as the paper states them ----
struct NaiveStump {
    int feature = -1;
    double threshold = 0;
    std::vector<int> sharing;
    double a = 0, b = 0;
    std::vector<double> k;
    double error = std::numeric_limits<double>::infinity();
    double h(int c, double v) const {
        const bool in = std::find(sharing.begin(), sharing.end(), c) != sharing.end();
        return in ? (v > threshold ? a : b) : k[c];
    }
};

// Fits a, b, k for (f, theta, S) and returns the weighted squared error, summed over samples
// and classes directly.
NaiveStump naive_fit(const FeatureTable& t, const std::vector<int>& y, const std::vector<std::vector<double>>& w, int f, double theta,
                     const std::vector<int>& set) {
    const int classes = static_cast<int>(w.size());
    NaiveStump s;
    s.feature = f, s.threshold = theta, s.sharing = set;
    double wa = 0, za = 0, wb = 0, zb = 0;
    for (int c : set)
        for (std::size_t i = 0; i < t.rows(); ++i) {
            const double z = y[i] == c ? 1 : -1;
            if (t.at(i, f) > theta)
                wa += w[c][i], za += w[c][i] * z;
            else
                wb += w[c][i], zb += w[c][i] * z;
        }
    s.a = za / wa, s.b = zb / wb;
    s.k.assign(classes, 0);
    for (int c = 0; c < classes; ++c) {
        double sw = 0, sz = 0;
        for (std::size_t i = 0; i < t.rows(); ++i) sw += w[c][i], sz += w[c][i] * (y[i] == c ? 1 : -1);
        s.k[c] = sz / sw;
    }
    s.error = 0;
    for (int c = 0; c < classes; ++c)
        for (std::size_t i = 0; i < t.rows(); ++i) {
            const double z = y[i] == c ? 1 : -1;
            const double d = z - s.h(c, t.at(i, f));
            s.error += w[c][i] * d * d;
        }
    return s;
}

NaiveStump naive_round(const FeatureTable& t, const std::vector<int>& y, const std::vector<std::vector<double>>& w) {
    const int classes = static_cast<int>(w.size());
    NaiveStump best;
    for (int f = 0; f < static_cast<int>(t.cols()); ++f) {
        std::vector<double> values;
        for (std::size_t i = 0; i < t.rows(); ++i) values.push_back(t.at(i, f));
        std::sort(values.begin(), values.end());
        values.erase(std::unique(values.begin(), values.end()), values.end());
        for (std::size_t v = 0; v + 1 < values.size(); ++v) {
            const double theta = (values[v] + values[v + 1]) / 2;
            std::vector<int> set;
            for (int step = 0; step < classes; ++step) {  // greedy forward selection
                NaiveStump step_best;
                for (int c = 0; c < classes; ++c) {
                    if (std::find(set.begin(), set.end(), c) != set.end()) continue;
                    auto trial = set;
                    trial.push_back(c);
                    std::sort(trial.begin(), trial.end());
                    auto s = naive_fit(t, y, w, f, theta, trial);
                    if (s.error < step_best.error - 1e-12) step_best = s;
                }
                set = step_best.sharing;
                if (step_best.error < best.error - 1e-12) best = step_best;
            }
        }
    }
    return best;
}

}  // namespace

TEST(JointBoost, SeparatesGaussianClusters) {
    FeatureTable train, test;
    std::vector<int> y_train, y_test;
    gaussian_clusters(6, 3, 40, 11, train, y_train);
    gaussian_clusters(6, 3, 40, 12, test, y_test);
    JointBoostReport report;
    const auto model = train_jointboost(train, y_train, class_names(6), {}, &report);
    EXPECT_GE(accuracy(model, train, y_train), 0.99);
    EXPECT_GE(accuracy(model, test, y_test), 0.96);
    EXPECT_GT(report.rounds, 0);
    EXPECT_LT(report.rounds_tried, 400);  // early stopping kicked in
    // The default model averages the 5 fold runs, each boosted on 4/5 of the trees: their late
    // rounds fit a little noise (measured: 15 of 435 stumps), which averaging dilutes.
    ASSERT_EQ(model.members.size(), 5u);
    for (const auto& member : model.members) EXPECT_EQ(member.stumps.size(), static_cast<std::size_t>(report.rounds));
    const auto stumps = all_stumps(model);
    int noise = 0;
    for (const auto& s : stumps) noise += s.feature == 3;
    EXPECT_LT(noise, static_cast<int>(stumps.size()) / 20);
    // Boosted again on all trees for the chosen rounds: the same bound.
    JointBoostOptions refit;
    refit.fold_ensemble = false;
    const auto single = train_jointboost(train, y_train, class_names(6), refit);
    EXPECT_GE(accuracy(single, test, y_test), 0.96);
    noise = 0;
    for (const auto& s : single.stumps) noise += s.feature == 3;
    EXPECT_LT(noise, static_cast<int>(single.stumps.size()) / 20);
}

// The rounds of fit_jointboost_rounds against the naive reference, stump by stump.
void expect_rounds_match_naive(const FeatureTable& t, const std::vector<int>& y, int classes, int rounds) {
    const auto model = fit_jointboost_rounds(t, y, class_names(classes), rounds);
    ASSERT_EQ(model.stumps.size(), static_cast<std::size_t>(rounds));
    std::vector<std::vector<double>> w(classes, std::vector<double>(t.rows(), 1.0));
    for (int m = 0; m < rounds; ++m) {
        const NaiveStump ref = naive_round(t, y, w);
        const Stump& s = model.stumps[m];
        SCOPED_TRACE("round " + std::to_string(m));
        EXPECT_EQ(s.feature, ref.feature);
        EXPECT_NEAR(s.threshold, ref.threshold, 1e-12);
        EXPECT_EQ(s.sharing, ref.sharing);
        EXPECT_NEAR(s.a, ref.a, 1e-9);
        EXPECT_NEAR(s.b, ref.b, 1e-9);
        for (int c = 0; c < classes; ++c) EXPECT_NEAR(s.k[c], ref.k[c], 1e-9);
        // Update the reference weights with the reference stump: w <- w exp(-z h).
        for (int c = 0; c < classes; ++c)
            for (std::size_t i = 0; i < t.rows(); ++i) w[c][i] *= std::exp(-(y[i] == c ? 1.0 : -1.0) * ref.h(c, t.at(i, ref.feature)));
    }
}

TEST(JointBoost, FirstRoundsMatchNaiveReference) {
    // Integer-valued features create repeated values (thresholds only between distinct values).
    Rng rng(5);
    FeatureTable t = empty_table(3);
    std::vector<int> y;
    for (int i = 0; i < 36; ++i) {
        const int c = i % 4;
        const double row[3] = {std::floor(rng.uniform(0, 6)) + (c == 1 ? 2 : 0), rng.normal() + 0.8 * c,
                               rng.normal() - (c >= 2 ? 1.5 : 0.0)};
        t.add_row(test::numbered("t", static_cast<std::size_t>(i)), row);
        y.push_back(c);
    }
    expect_rounds_match_naive(t, y, 4, 4);
}

TEST(JointBoost, ManyRoundsOverManyFeaturesMatchNaiveReference) {
    // The fast search visits features in the order of their previous round's bound and prunes
    // thresholds against the best gain of any feature so far; over many rounds the order changes
    // and duplicated columns tie exactly (the lower index must win), yet every stump must be the
    // exhaustive search's.
    Rng rng(17);
    const int classes = 5, features = 9;
    FeatureTable t = empty_table(features);
    std::vector<int> y;
    for (int i = 0; i < 45; ++i) {
        const int c = i % classes;
        double row[features];
        row[0] = rng.normal() + 0.6 * c;
        row[1] = std::floor(rng.uniform(0, 5)) + (c == 3 ? 2 : 0);
        row[2] = rng.normal() - (c <= 1 ? 1.2 : 0.0);
        row[3] = rng.normal();  // noise
        row[4] = row[2];        // duplicate of feature 2: exact ties
        row[5] = rng.normal() + (c == 4 ? 1.5 : 0.0);
        row[6] = std::floor(rng.uniform(0, 3));  // few distinct values
        row[7] = rng.normal() * (1.0 + 0.3 * c);
        row[8] = row[0];  // duplicate of feature 0
        t.add_row(test::numbered("t", static_cast<std::size_t>(i)), row);
        y.push_back(c);
    }
    expect_rounds_match_naive(t, y, classes, 14);
}

TEST(JointBoost, ClassesWithACommonFeatureShareTheFirstStump) {
    // Classes 0 and 1 are the only ones with a high feature 0; classes 2, 3, 4 differ on other
    // features. The best first stump is feature 0 shared by {0, 1}: below the threshold every
    // tree is a negative for both, which one shared stump says at once (gain 11.4 n against 10.2 n
    // for a single class and 9 n for all classes; see the derivation in docs/classify.md).
    Rng rng(3);
    FeatureTable t = empty_table(4);
    std::vector<int> y;
    for (int i = 0; i < 30; ++i)
        for (int c = 0; c < 5; ++c) {
            double row[4] = {rng.normal(0, 0.3), rng.normal(0, 0.3), rng.normal(0, 0.3), rng.normal(0, 0.3)};
            if (c <= 1) row[0] += 5;
            if (c >= 1 && c <= 3) row[c] += 0.6;  // weak single-class cues (2 sigma)
            t.add_row(test::numbered("t", static_cast<std::size_t>(t.rows())), row);
            y.push_back(c);
        }
    const auto model = fit_jointboost_rounds(t, y, class_names(5), 30);
    ASSERT_FALSE(model.stumps.empty());
    const Stump& first = model.stumps.front();
    EXPECT_EQ(first.feature, 0);
    EXPECT_EQ(first.sharing, (std::vector<int>{0, 1}));
    EXPECT_NEAR(first.a, 0.0, 1e-9);      // above: half positives of class 0, half of class 1
    EXPECT_NEAR(first.b, -1.0, 1e-9);     // below: only negatives for both
    EXPECT_NEAR(first.k[2], -0.6, 1e-9);  // k_c: (n - 4n) / 5n
    EXPECT_GE(accuracy(model, t, y), 0.8);
}

TEST(JointBoost, DeterministicAndIndependentOfThreads) {
    FeatureTable t;
    std::vector<int> y;
    gaussian_clusters(5, 3, 20, 21, t, y);
    TempDir dir;
    save_jointboost(train_jointboost(t, y, class_names(5), {}), dir / "a.jb");
    {
        tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
        save_jointboost(train_jointboost(t, y, class_names(5), {}), dir / "b.jb");
    }
    EXPECT_EQ(read_file(dir / "a.jb"), read_file(dir / "b.jb"));
}

TEST(JointBoost, EarlyStoppingOnNoise) {
    Rng rng(8);
    FeatureTable t = empty_table(5);
    std::vector<int> y;
    for (int i = 0; i < 120; ++i) {
        double row[5];
        for (double& v : row) v = rng.normal();
        t.add_row(test::numbered("t", static_cast<std::size_t>(i)), row);
        y.push_back(static_cast<int>(rng.below(3)));
    }
    JointBoostOptions options;
    options.max_rounds = 300;
    options.patience = 25;
    JointBoostReport report;
    train_jointboost(t, y, class_names(3), options, &report);
    EXPECT_LT(report.rounds_tried, 300);
    EXPECT_LE(report.rounds, report.rounds_tried - 25 + 1);
    EXPECT_EQ(report.validation_error.size(), static_cast<std::size_t>(report.rounds_tried));
    // The training loss keeps falling while the validation error does not: boosting memorises noise.
    EXPECT_LT(report.training_loss.back(), 0.8 * report.training_loss.front());
    EXPECT_GT(*std::min_element(report.validation_error.begin(), report.validation_error.end()), 0.3);
}

TEST(JointBoost, ProbabilitiesStayDefinedWhenEveryScoreIsFarBelowZero) {
    const auto p = probabilities_from_scores({-900.0, -1000.0, -1000.0}, 0.25);
    EXPECT_NEAR(p[0], 1.0, 1e-12);  // sigma ratios: e^(2 * 100 / 0.25) in favour of class 0
    const auto q = probabilities_from_scores({-1000.0, -1000.0}, 1.0);
    EXPECT_NEAR(q[0], 0.5, 1e-12);
}

TEST(JointBoost, ProbabilitiesAreTheNormalisedLogisticOf2H) {
    const std::vector<double> h = {0.5, -0.2, 1.5};
    const auto p = probabilities_from_scores(h);
    double sum = 0;
    for (double v : p) sum += v;
    EXPECT_NEAR(sum, 1.0, 1e-12);
    const double s0 = 1 / (1 + std::exp(-1.0)), s1 = 1 / (1 + std::exp(0.4)), s2 = 1 / (1 + std::exp(-3.0));
    EXPECT_NEAR(p[0], s0 / (s0 + s1 + s2), 1e-12);
    EXPECT_GT(p[2], p[0]);
    EXPECT_GT(p[0], p[1]);
}

TEST(JointBoost, TemperatureSoftensOverconfidentScoresAndSharpensTimidOnes) {
    // Three classes; the scores always favour class 0 by a margin, the labels agree with them on
    // 7 of 10 trees (overconfident at a margin of 3) or on all trees (timid at a margin of 0.1).
    std::vector<std::vector<double>> bold, timid;
    std::vector<int> noisy, exact;
    for (int i = 0; i < 10; ++i) {
        bold.push_back({3.0, -3.0, -3.0});
        noisy.push_back(i < 7 ? 0 : 1 + i % 2);
        timid.push_back({0.1, -0.1, -0.1});
        exact.push_back(0);
    }
    const double soft = fit_temperature(bold, noisy), sharp = fit_temperature(timid, exact);
    EXPECT_GT(soft, 2.0);
    EXPECT_LT(sharp, 0.5);
    // The fitted temperature gives the held-out trees about their observed accuracy.
    EXPECT_NEAR(probabilities_from_scores(bold.front(), soft)[0], 0.7, 0.05);
    EXPECT_EQ(probabilities_from_scores({0.5, -0.2}, 1.0), probabilities_from_scores({0.5, -0.2}));
}

TEST(JointBoost, ModelFileRoundTripsAndRejectsBadFiles) {
    FeatureTable t;
    std::vector<int> y;
    gaussian_clusters(4, 2, 25, 31, t, y);
    const auto model = train_jointboost(t, y, class_names(4), {});
    TempDir dir;
    save_jointboost(model, dir / "m.jb");
    const auto loaded = load_jointboost(dir / "m.jb");
    EXPECT_EQ(loaded.feature_names, t.feature_names);
    ASSERT_EQ(all_stumps(loaded).size(), all_stumps(model).size());
    ASSERT_EQ(loaded.members.size(), model.members.size());
    for (std::size_t r = 0; r < t.rows(); ++r) EXPECT_EQ(loaded.scores(t.row(r)), model.scores(t.row(r)));
    EXPECT_EQ(loaded.temperature, model.temperature);
    for (std::size_t r = 0; r < t.rows(); ++r) EXPECT_EQ(loaded.probabilities(t.row(r)), model.probabilities(t.row(r)));

    std::string text = read_file(dir / "m.jb");
    test::write_text(dir / "v4.jb", std::string(text).replace(text.find("\"version\": 3"), 12, "\"version\": 4"));
    try {
        load_jointboost(dir / "v4.jb");
        FAIL() << "version 4 accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("version 4"), std::string::npos);
    }
    // Version 2 files (a single stump list, as --refit and --average-scores still write) load as
    // they are.
    JointBoostOptions flat;
    flat.average_probabilities = false;
    const auto single = train_jointboost(t, y, class_names(4), flat);
    EXPECT_TRUE(single.members.empty());
    save_jointboost(single, dir / "s.jb");
    const std::string flat_text = read_file(dir / "s.jb");
    test::write_text(dir / "v2.jb", std::string(flat_text).replace(flat_text.find("\"version\": 3"), 12, "\"version\": 2"));
    EXPECT_EQ(load_jointboost(dir / "v2.jb").probabilities(t.row(0)), single.probabilities(t.row(0)));
    // Version 1 files (before the temperature) still load, with T = 1.
    std::string v1 = std::string(text).replace(text.find("\"version\": 3"), 12, "\"version\": 1");
    v1.replace(v1.find("\"temperature\": "), 15, "\"old_temperature\": ");
    test::write_text(dir / "v1.jb", v1);
    EXPECT_EQ(load_jointboost(dir / "v1.jb").temperature, 1.0);
    test::write_text(dir / "junk.jb", "{\"format\": \"treelobes-jointboost\", \"version\": 1, \"classes\": [\"a\"");
    EXPECT_THROW(load_jointboost(dir / "junk.jb"), Error);
    test::write_text(dir / "bad_index.jb", std::string(text).replace(text.find("\"feature\": "), 12, "\"feature\": 9"));
    EXPECT_EQ(test::error_code_of([&] { load_jointboost(dir / "bad_index.jb"); }), ExitCode::InvalidInput);
    // Wrong types, truncation and other files: always a one-line input error, never a crash.
    for (const std::string& bad :
         {std::string("{\"format\": 3, \"version\": 1}"), std::string("{\"format\": \"treelobes-jointboost\", \"version\": \"1\"}"),
          std::string("[1, 2]"), std::string(""), text.substr(0, text.size() / 2),
          std::string(text).replace(text.find("\"k\": ["), 6, "\"k\": [\"x\", "),
          // Numbers no int holds (a fuzzer's find: converting 6.7e25 to int was undefined).
          std::string(text).replace(text.find("\"feature\": "), 11, "\"feature\": 66666666666666666666666661, \"f\": "),
          std::string(text).replace(text.find("\"feature\": "), 11, "\"feature\": 1.5, \"f\": "),
          std::string(text).replace(text.find("\"sharing\": ["), 12, "\"sharing\": [4294967296, "),
          std::string(text).replace(text.find("\"version\": 3"), 12, "\"version\": 4294967299")}) {
        test::write_text(dir / "bad.jb", bad);
        EXPECT_EQ(test::error_code_of([&] { load_jointboost(dir / "bad.jb"); }), ExitCode::InvalidInput) << bad.substr(0, 80);
    }
    EXPECT_EQ(test::error_code_of([&] { load_jointboost(dir / "missing.jb"); }), ExitCode::InvalidInput);
}

TEST(JointBoost, RejectsBadTrainingInput) {
    FeatureTable t = empty_table(2);
    const double a[2] = {1, 2}, b[2] = {std::numeric_limits<double>::infinity(), 3};  // NaN is a missing value, infinity an error
    t.add_row("x", a);
    t.add_row("y", a);
    EXPECT_THROW(train_jointboost(t, {0, 0}, class_names(1), {}), Error);
    t.add_row("z", b);
    EXPECT_THROW(train_jointboost(t, {0, 1, 1}, class_names(2), {}), Error);
    EXPECT_THROW(train_jointboost(t, {0, 0, 0}, class_names(2), {}), Error);  // class 1 has no trees
}

TEST(JointBoost, RejectsANonFiniteSettledLogLoss) {
    FeatureTable t = empty_table(2);
    for (int r = 0; r < 8; ++r) {
        const double v[2] = {static_cast<double>(r), static_cast<double>(r % 3)};
        t.add_row("t" + std::to_string(r), v);
    }
    const std::vector<int> y{0, 0, 0, 0, 1, 1, 1, 1};
    for (double bad : {std::nan(""), std::numeric_limits<double>::infinity(), -0.5}) {
        JointBoostOptions o;
        o.folds = 2;
        o.settled_logloss = bad;
        EXPECT_EQ(test::error_code_of([&] { train_jointboost(t, y, class_names(2), o); }), ExitCode::Usage) << bad;
    }
}

namespace {

// Two scan kinds in one table: feature f0 tells the classes apart in the sparse kind and f1 in
// the dense kind, with the opposite sign, so that no single threshold of either serves both; the
// scan descriptor (tens against thousands of points per m^2) tells the kinds apart.
void two_scan_kinds(int per_class_and_kind, std::uint64_t seed, FeatureTable& table, std::vector<int>& y) {
    Rng rng(seed);
    table = empty_table(3);
    table.feature_names.push_back(kScanDensityFeature);
    for (int i = 0; i < per_class_and_kind; ++i)
        for (int kind = 0; kind < 2; ++kind)
            for (int c = 0; c < 3; ++c) {
                double row[4] = {rng.normal(), rng.normal(), rng.normal(),
                                 kind == 0 ? 40.0 + 100.0 * rng.uniform() : 900.0 + 9000.0 * rng.uniform()};
                row[kind] += (kind == 0 ? 4.0 : -4.0) * (c - 1);
                table.add_row(test::numbered("t", table.rows()), row);
                y.push_back(c);
            }
}

}  // namespace

TEST(JointBoost, RoutesTreesToOneSubModelPerScanKind) {
    FeatureTable t;
    std::vector<int> y;
    two_scan_kinds(15, 5, t, y);
    JointBoostReport report;
    const auto model = train_jointboost(t, y, class_names(3), {}, &report);
    ASSERT_TRUE(model.routed());
    ASSERT_EQ(model.parts.size(), 2u);
    EXPECT_EQ(model.route_feature, 3);
    EXPECT_GT(model.route_threshold, 140.0);  // in the gap, the geometric mean of its ends
    EXPECT_LT(model.route_threshold, 900.0);
    EXPECT_EQ(report.parts.size(), 2u);
    EXPECT_EQ(report.rounds, report.parts[0].rounds + report.parts[1].rounds);
    for (const auto& part : model.parts) {
        EXPECT_EQ(part.classes, class_names(3));
        ASSERT_FALSE(part.members.empty());
        for (const auto& s : all_stumps(part)) EXPECT_NE(s.feature, 3) << "the scan descriptor is not a tree feature";
    }
    // The sparse part splits on f0, the dense one on f1 (their own informative feature).
    EXPECT_EQ(model.parts[0].members.front().stumps.front().feature, 0);
    EXPECT_EQ(model.parts[1].members.front().stumps.front().feature, 1);
    FeatureTable test_set;
    std::vector<int> test_y;
    two_scan_kinds(10, 6, test_set, test_y);
    EXPECT_GE(accuracy(model, test_set, test_y), 0.9);
    // A tree is served by the part of its density: the same vector at the other density is read
    // with the other part's feature.
    std::vector<double> sparse(test_set.row(0), test_set.row(0) + 4), dense = sparse;
    dense[3] = 5000;
    EXPECT_EQ(model.part_index(sparse.data()), 0u);
    EXPECT_EQ(model.part_index(dense.data()), 1u);
    EXPECT_EQ(model.probabilities(sparse.data()), model.parts[0].probabilities(sparse.data()));
    EXPECT_EQ(model.probabilities(dense.data()), model.parts[1].probabilities(dense.data()));

    // Without routing, one model over the same trees (the descriptor still unused).
    JointBoostOptions single;
    single.route_by_scan = false;
    const auto one = train_jointboost(t, y, class_names(3), single);
    EXPECT_FALSE(one.routed());
    for (const auto& s : all_stumps(one)) EXPECT_NE(s.feature, 3);
}

TEST(JointBoost, NoRoutingWithoutTwoDensityClusters) {
    FeatureTable t;
    std::vector<int> y;
    two_scan_kinds(15, 7, t, y);
    // All densities within a factor 3 of each other: one model.
    for (std::size_t r = 0; r < t.rows(); ++r) t.values[r * t.cols() + 3] = 100.0 + static_cast<double>(r);
    EXPECT_EQ(choose_scan_routing(t, y, {}).first, -1);
    EXPECT_FALSE(train_jointboost(t, y, class_names(3), {}).routed());
    // Two clusters, but one side holds fewer than route_min_trees trees: one model.
    for (std::size_t r = 0; r < t.rows(); ++r) t.values[r * t.cols() + 3] = r < 10 ? 50.0 : 5000.0;
    EXPECT_EQ(choose_scan_routing(t, y, {}).first, -1);
    JointBoostOptions few;
    few.route_min_trees = 10;
    EXPECT_EQ(choose_scan_routing(t, y, few).first, 3);
}

TEST(JointBoost, RoutedModelFileRoundTripsWithTwoSubModels) {
    FeatureTable t;
    std::vector<int> y;
    two_scan_kinds(12, 9, t, y);
    // Class 2 only in the dense kind: the sparse part has two classes and gives class 2 nothing.
    FeatureTable kept = empty_table(0);
    kept.feature_names = t.feature_names;
    std::vector<int> kept_y;
    for (std::size_t r = 0; r < t.rows(); ++r)
        if (!(y[r] == 2 && t.at(r, 3) < 500)) kept.add_row(t.ids[r], std::span<const double>(t.row(r), t.cols())), kept_y.push_back(y[r]);
    const auto model = train_jointboost(kept, kept_y, class_names(3), {});
    ASSERT_TRUE(model.routed());
    EXPECT_EQ(model.parts[0].classes, (std::vector<std::string>{"class0", "class1"}));
    EXPECT_EQ(model.part_class_ids[0], (std::vector<int>{0, 1}));
    TempDir dir;
    save_jointboost(model, dir / "routed.jb");
    const std::string text = read_file(dir / "routed.jb");
    EXPECT_NE(text.find("\"version\": 3"), std::string::npos);
    EXPECT_NE(text.find("\"routing\""), std::string::npos);
    const auto loaded = load_jointboost(dir / "routed.jb");
    ASSERT_TRUE(loaded.routed());
    EXPECT_EQ(loaded.route_feature, model.route_feature);
    EXPECT_EQ(loaded.route_threshold, model.route_threshold);
    EXPECT_EQ(loaded.part_class_ids, model.part_class_ids);
    for (std::size_t r = 0; r < t.rows(); ++r) {
        const auto p = loaded.probabilities(t.row(r));
        EXPECT_EQ(p, model.probabilities(t.row(r)));
        if (t.at(r, 3) < 500) {
            EXPECT_EQ(p[2], 0.0);
        }
    }
    // A routed file naming an unknown routing feature or part class, or declaring version 2
    // (single models only): input errors.
    const auto part_class = text.find("\"class1\"", text.find("\"models\""));
    ASSERT_NE(part_class, std::string::npos);
    for (const auto& [at, from, to] : std::vector<std::tuple<std::size_t, std::string, std::string>>{
                 {text.find("\"feature\": \"scan_point_density\""), "\"feature\": \"scan_point_density\"", "\"feature\": \"nope\""},
                 {part_class, "\"class1\"", "\"class7\""},
                 {text.find("\"version\": 3"), "\"version\": 3", "\"version\": 2"}}) {
        ASSERT_NE(at, std::string::npos) << from;
        test::write_text(dir / "bad.jb", std::string(text).replace(at, from.size(), to));
        EXPECT_EQ(test::error_code_of([&] { load_jointboost(dir / "bad.jb"); }), ExitCode::InvalidInput) << to;
    }
}

// The fold ensemble averaging probabilities keeps its members (one per fold) in the model and the
// file; a tree the members disagree on gets their mean probabilities, not those of their mean H.
TEST(JointBoost, ProbabilityAveragingEnsembleKeepsItsMembersThroughTheFile) {
    FeatureTable t;
    std::vector<int> y;
    two_scan_kinds(12, 11, t, y);
    JointBoostOptions options;
    options.average_probabilities = true;
    const auto model = train_jointboost(t, y, class_names(3), options);
    ASSERT_TRUE(model.routed());
    for (const auto& part : model.parts) {
        EXPECT_EQ(part.members.size(), static_cast<std::size_t>(options.folds));
        EXPECT_TRUE(part.stumps.empty());
    }
    const double* row = t.row(0);
    const auto& part = model.parts[model.part_index(row)];
    std::vector<double> mean(part.class_count(), 0.0);
    for (const auto& member : part.members) {
        const auto p = probabilities_from_scores(member.scores(row), part.temperature);
        for (std::size_t c = 0; c < mean.size(); ++c) mean[c] += p[c] / static_cast<double>(part.members.size());
    }
    const auto p = part.probabilities(row);
    for (std::size_t c = 0; c < mean.size(); ++c) EXPECT_NEAR(p[c], mean[c], 1e-12);
    TempDir dir;
    save_jointboost(model, dir / "members.jb");
    const auto loaded = load_jointboost(dir / "members.jb");
    ASSERT_TRUE(loaded.routed());
    EXPECT_EQ(loaded.parts[1].members.size(), model.parts[1].members.size());
    for (std::size_t r = 0; r < t.rows(); ++r) EXPECT_EQ(loaded.probabilities(t.row(r)), model.probabilities(t.row(r)));
    const std::string text = read_file(dir / "members.jb");
    const auto at = text.find("\"members\": [");
    ASSERT_NE(at, std::string::npos);
    test::write_text(dir / "bad.jb", std::string(text).replace(at, 13, "\"members\": 7, \"x\": ["));
    EXPECT_EQ(test::error_code_of([&] { load_jointboost(dir / "bad.jb"); }), ExitCode::InvalidInput);
}

// Missing values (NaN: a feature that could not be computed) go to the side of the threshold that
// fits best, learnt per stump. Class 0 trees have feature 0 missing or high, class 1 trees low:
// one stump separates them only if the missing values go above, with the high ones.
TEST(JointBoost, LearnsWhichSideMissingValuesGo) {
    FeatureTable t = empty_table(2);
    std::vector<int> y;
    Rng rng(3);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (int i = 0; i < 30; ++i) {
        const double missing_or_high[2] = {i % 2 ? nan : rng.uniform(3, 4), rng.normal()};
        const double low[2] = {rng.uniform(0, 1), rng.normal()};
        t.add_row(test::numbered("a", static_cast<std::size_t>(i)), missing_or_high), y.push_back(0);
        t.add_row(test::numbered("b", static_cast<std::size_t>(i)), low), y.push_back(1);
    }
    const JointBoostModel one = fit_jointboost_rounds(t, y, class_names(2), 1);
    ASSERT_EQ(one.stumps.size(), 1u);
    EXPECT_EQ(one.stumps[0].feature, 0);
    EXPECT_TRUE(one.stumps[0].missing_above);
    for (std::size_t r = 0; r < t.rows(); ++r) {
        const auto p = one.probabilities(t.row(r));
        EXPECT_EQ(p[0] > p[1] ? 0 : 1, y[r]) << t.ids[r];
    }
    // A new tree without feature 0 is taken for class 0; the direction survives the model file.
    const double unseen[2] = {nan, 0.0};
    TempDir dir;
    save_jointboost(one, dir / "m.jb");
    const JointBoostModel back = load_jointboost(dir / "m.jb");
    EXPECT_TRUE(back.stumps[0].missing_above);
    EXPECT_GT(back.probabilities(unseen)[0], 0.5);
    EXPECT_EQ(back.probabilities(unseen), one.probabilities(unseen));
    // The full training (cross-validated ensemble) takes the table with missing values too.
    const JointBoostModel model = train_jointboost(t, y, class_names(2), {});
    EXPECT_GT(model.probabilities(unseen)[0], 0.5);
}

// Class weights: with 40 trees of class 0 and 4 of class 1 whose feature overlaps, the balanced
// model recognises the rare class better than the unweighted one, and a balanced set is unchanged.
TEST(JointBoost, BalancedClassWeightsFavourTheRareClass) {
    FeatureTable t = empty_table(1);
    std::vector<int> y;
    Rng rng(8);
    for (int i = 0; i < 40; ++i) {
        const double v[1] = {rng.normal(0, 1)};
        t.add_row(test::numbered("a", static_cast<std::size_t>(i)), v), y.push_back(0);
    }
    for (int i = 0; i < 4; ++i) {
        const double v[1] = {rng.normal(1.5, 1)};
        t.add_row(test::numbered("b", static_cast<std::size_t>(i)), v), y.push_back(1);
    }
    JointBoostOptions plain, balanced;
    plain.folds = balanced.folds = 0;
    plain.max_rounds = balanced.max_rounds = 3;
    plain.balance_classes = false;
    const auto rare_votes = [&](const JointBoostModel& m) {
        int n = 0;
        for (std::size_t r = 0; r < t.rows(); ++r) {
            const auto p = m.probabilities(t.row(r));
            n += p[1] > p[0];
        }
        return n;
    };
    EXPECT_GT(rare_votes(train_jointboost(t, y, class_names(2), balanced)), rare_votes(train_jointboost(t, y, class_names(2), plain)));
    FeatureTable even;
    std::vector<int> even_y;
    gaussian_clusters(3, 2, 10, 4, even, even_y);
    JointBoostOptions even_plain = plain, even_balanced = balanced;
    even_plain.max_rounds = even_balanced.max_rounds = 20;
    const auto a = train_jointboost(even, even_y, class_names(3), even_plain),
               b = train_jointboost(even, even_y, class_names(3), even_balanced);
    ASSERT_EQ(a.stumps.size(), b.stumps.size());
    for (std::size_t k = 0; k < a.stumps.size(); ++k) EXPECT_EQ(a.stumps[k].threshold, b.stumps[k].threshold);
}
