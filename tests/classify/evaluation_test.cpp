// The evaluation protocol, splits, spatial voting, the report files and the CSV tables, on small
// hand-made feature tables with known answers (no point clouds: milliseconds).
#include "classify/evaluation.hpp"
#include "classify/feature_table.hpp"
#include "classify/jointboost.hpp"
#include "classify/splits.hpp"
#include "classify/voting.hpp"
#include "classify/xgboost_baseline.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/random.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <set>

using namespace treelobes;
using namespace treelobes::classify;
using treelobes::test::TempDir;

namespace {

// `per_class` trees per class; class c is centred at 3c on feature 0 with noise `sigma`, feature 1
// is noise. Positions: same-species rows along streets 300 m apart (class c from x = 300 c, 8 m apart) when
// `grouped`, otherwise scattered at random over the same area.
LabelledSet clustered_set(int classes, int per_class, double sigma, bool grouped, std::uint64_t seed) {
    Rng rng(seed);
    LabelledSet set;
    set.features.feature_names = {"f0", "f1"};
    for (int c = 0; c < classes; ++c) set.classes.push_back("species" + std::to_string(c));
    for (int i = 0; i < per_class; ++i)
        for (int c = 0; c < classes; ++c) {
            const double row[2] = {3.0 * c + rng.normal(0, sigma), rng.normal()};
            set.features.add_row(test::numbered("t", static_cast<std::size_t>(set.features.rows())), row);
            set.labels.push_back(c);
            const double x = grouped ? 300.0 * c + 8.0 * i : rng.uniform(0, 300.0 * classes);
            set.positions.emplace_back(x, grouped ? 0.0 : rng.uniform(0, 100));
        }
    return set;
}

// Nearest class mean on feature 0, probabilities from a softmax of -distance^2 / 2 (a classifier
// whose mistakes and confidences are easy to reason about).
NamedClassifier nearest_mean() {
    return {"nearest", [](const FeatureTable& train, const std::vector<int>& y, int classes, const FeatureTable& test, std::uint64_t) {
                std::vector<double> sum(classes, 0), count(classes, 0);
                for (std::size_t r = 0; r < train.rows(); ++r) sum[y[r]] += train.at(r, 0), count[y[r]] += 1;
                ClassifierRun run;
                run.rounds = 1;
                for (std::size_t r = 0; r < test.rows(); ++r) {
                    std::vector<double> p(classes);
                    double total = 0;
                    for (int c = 0; c < classes; ++c) {
                        const double d = test.at(r, 0) - sum[c] / count[c];
                        total += p[c] = std::exp(-d * d / 2);
                    }
                    for (double& v : p) v /= total;
                    run.probabilities.push_back(p);
                }
                return run;
            }};
}

NamedClassifier always_first() {
    return {"first", [](const FeatureTable&, const std::vector<int>&, int classes, const FeatureTable& test, std::uint64_t) {
                ClassifierRun run;
                std::vector<double> p(classes, 0.0);
                p[0] = 1.0;
                run.probabilities.assign(test.rows(), p);
                return run;
            }};
}

}  // namespace

TEST(ClassifySplits, StratifiedFoldsAreBalancedAndSeeded) {
    std::vector<int> labels;
    for (int i = 0; i < 41; ++i) labels.push_back(i % 3);  // 14, 14, 13 trees
    const auto folds = stratified_folds(labels, 3, 3, 5);
    ASSERT_EQ(folds.size(), labels.size());
    std::vector<std::vector<int>> count(3, std::vector<int>(3, 0));  // [class][fold]
    for (std::size_t i = 0; i < labels.size(); ++i) {
        ASSERT_GE(folds[i], 0);
        ASSERT_LT(folds[i], 3);
        ++count[labels[i]][folds[i]];
    }
    for (const auto& per_fold : count)
        EXPECT_LE(*std::max_element(per_fold.begin(), per_fold.end()) - *std::min_element(per_fold.begin(), per_fold.end()), 1);
    EXPECT_EQ(stratified_folds(labels, 3, 3, 5), folds);
    EXPECT_NE(stratified_folds(labels, 3, 3, 6), folds);
}

TEST(ClassifySplits, StratifiedHalvesAreDisjointCompleteAndSeeded) {
    std::vector<int> labels;
    for (int i = 0; i < 41; ++i) labels.push_back(i % 3);  // 14, 14, 13 trees
    std::vector<std::size_t> a, b, a2, b2, a3, b3;
    stratified_split(labels, 3, 0.5, 7, true, a, b);
    std::vector<int> per_class(3, 0);
    for (auto r : a) ++per_class[labels[r]];
    EXPECT_EQ(per_class, (std::vector<int>{7, 7, 6}));
    std::set<std::size_t> all(a.begin(), a.end());
    all.insert(b.begin(), b.end());
    EXPECT_EQ(all.size(), labels.size());
    EXPECT_EQ(a.size() + b.size(), labels.size());
    stratified_split(labels, 3, 0.5, 7, true, a2, b2);
    EXPECT_EQ(a, a2);
    stratified_split(labels, 3, 0.5, 8, true, a3, b3);
    EXPECT_NE(a, a3);
    // A class of two trees keeps one on each side even with a tiny fraction.
    stratified_split({0, 0, 1, 1}, 2, 0.1, 1, true, a, b);
    EXPECT_EQ(a.size(), 2u);
    EXPECT_EQ(b.size(), 2u);
}

TEST(ClassifyEvaluation, PerSpeciesRatesConfusionAndSplitCounts) {
    const LabelledSet set = clustered_set(3, 10, 0.3, true, 1);
    EvaluationOptions options;
    options.splits = 7;
    const auto report = evaluate(set, {nearest_mean(), always_first()}, options);
    ASSERT_EQ(report.classifiers.size(), 2u);
    const Scores& good = report.classifiers[0].random_splits;
    EXPECT_EQ(good.experiments, 7);
    EXPECT_EQ(good.species_train, (std::vector<int>{5, 5, 5}));
    EXPECT_EQ(good.species_trees, (std::vector<int>{10, 10, 10}));
    EXPECT_DOUBLE_EQ(good.average_rate, 1.0);  // classes 10 sigma apart
    double total = 0;
    for (const auto& row : good.confusion)
        for (double v : row) total += v;
    EXPECT_DOUBLE_EQ(total, 7.0 * 15);  // every test tree of every split
    EXPECT_DOUBLE_EQ(good.confident_fraction, 1.0);

    const Scores& bad = report.classifiers[1].random_splits;
    EXPECT_EQ(bad.species_rate, (std::vector<double>{1.0, 0.0, 0.0}));
    EXPECT_NEAR(bad.average_rate, 1.0 / 3, 1e-12);
    for (int c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ(bad.confusion[c][0], 7.0 * 5);
}

// The splits run side by side; the report is scored in split order, so it is the same with one
// thread as with many (JointBoost with a cross-validation ensemble, noisy classes so that some
// trees are wrong and unconfident).
TEST(ClassifyEvaluation, ParallelSplitsGiveTheSameReportAsOneThread) {
    const LabelledSet set = clustered_set(4, 12, 1.2, true, 3);
    EvaluationOptions options;
    options.splits = 6;
    JointBoostOptions jb;
    jb.fold_ensemble = true;
    jb.max_rounds = 60;
    const NamedClassifier jointboost = {"JointBoost", [jb](const FeatureTable& train, const std::vector<int>& y, int classes,
                                                           const FeatureTable& test, std::uint64_t seed) {
                                            JointBoostOptions o = jb;
                                            o.seed = seed;
                                            std::vector<std::string> names;
                                            for (int c = 0; c < classes; ++c) names.push_back(std::to_string(c));
                                            const auto model = train_jointboost(train, y, names, o);
                                            ClassifierRun run;
                                            for (std::size_t r = 0; r < test.rows(); ++r)
                                                run.probabilities.push_back(model.probabilities(test.row(r)));
                                            return run;
                                        }};
    const auto many = evaluate(set, {jointboost}, options).classifiers[0].random_splits;
    Scores one;
    {
        tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
        one = evaluate(set, {jointboost}, options).classifiers[0].random_splits;
    }
    EXPECT_EQ(many.row_predictions, one.row_predictions);
    EXPECT_EQ(many.confusion, one.confusion);
    EXPECT_EQ(many.voted_species_rate, one.voted_species_rate);
    EXPECT_EQ(many.confident_fraction, one.confident_fraction);
    EXPECT_LT(many.average_rate, 1.0);
    EXPECT_GT(many.average_rate, 0.5);
}

TEST(ClassifyEvaluation, AverageRateIsTheMeanOfSpeciesRatesNotTreeAccuracy) {
    // Unbalanced classes: 20 trees of species 0, 4 of species 1; "always species 0" is right for
    // 10 of 12 test trees but recognises only one species in two.
    LabelledSet set;
    set.features.feature_names = {"f"};
    set.classes = {"a", "b"};
    for (int i = 0; i < 24; ++i) {
        const double v = i;
        set.features.add_row(test::numbered("t", static_cast<std::size_t>(i)), {&v, 1});
        set.labels.push_back(i < 20 ? 0 : 1);
    }
    EvaluationOptions options;
    options.splits = 3;
    const auto s = evaluate(set, {always_first()}, options).classifiers[0].random_splits;
    EXPECT_DOUBLE_EQ(s.average_rate, 0.5);
    EXPECT_NEAR(s.tree_accuracy, 10.0 / 12, 1e-12);
}

TEST(ClassifyEvaluation, SiteSplitTestsEachGroupOnTheOthers) {
    LabelledSet set = clustered_set(2, 9, 0.3, true, 2);
    for (std::size_t r = 0; r < set.labels.size(); ++r) set.groups.push_back("tile" + std::to_string(r % 3));
    std::vector<std::pair<std::size_t, std::size_t>> sizes;  // (train, test) rows seen by the classifier
    std::mutex sizes_mutex;                                  // the splits run in parallel (ThreadSanitizer found the unguarded push)
    NamedClassifier spy = nearest_mean();
    const Classifier inner = spy.run;
    spy.run = [&](const FeatureTable& train, const std::vector<int>& y, int classes, const FeatureTable& test, std::uint64_t seed) {
        {
            const std::lock_guard lock(sizes_mutex);
            sizes.emplace_back(train.rows(), test.rows());
        }
        for (const auto& id : test.ids) EXPECT_FALSE(train.find(id)) << id << " is in both sets";
        return inner(train, y, classes, test, seed);
    };
    EvaluationOptions options;
    options.splits = 2;
    const auto report = evaluate(set, {spy}, options);
    EXPECT_EQ(report.site_groups, (std::vector<std::string>{"tile0", "tile1", "tile2"}));
    const Scores& site = report.classifiers[0].site_split;
    EXPECT_EQ(site.experiments, 3);
    ASSERT_EQ(sizes.size(), 5u);  // 2 random splits, then 3 groups
    for (std::size_t k = 2; k < 5; ++k) EXPECT_EQ(sizes[k], std::make_pair(std::size_t(12), std::size_t(6)));
    EXPECT_DOUBLE_EQ(site.average_rate, 1.0);
    options.site_split = false;
    EXPECT_EQ(evaluate(set, {nearest_mean()}, options).classifiers[0].site_split.experiments, 0);
}

TEST(ClassifyEvaluation, RejectsASpeciesWithOneTree) {
    LabelledSet set = clustered_set(2, 3, 0.3, true, 3);
    set.labels.back() = 2;
    set.classes.push_back("lonely");
    EXPECT_EQ(test::error_code_of([&] { evaluate(set, {nearest_mean()}, {}); }), ExitCode::InvalidInput);
    EvaluationOptions zero;
    zero.splits = 0;
    EXPECT_EQ(test::error_code_of([&] { evaluate(clustered_set(2, 3, 0.3, true, 3), {nearest_mean()}, zero); }), ExitCode::Usage);
}

TEST(ClassifyVoting, UnconfidentTreesTakeTheMostProbableNeighbourSpecies) {
    // Tree 0 is unsure (B 0.40 > A 0.35 > C 0.25); its confident neighbours are A and C, so it
    // becomes A. Tree 3 is unsure but alone beyond the radius and keeps its own best guess.
    const std::vector<std::vector<double>> p = {
            {0.35, 0.40, 0.25}, {0.9, 0.05, 0.05}, {0.1, 0.1, 0.8}, {0.32, 0.45, 0.23}, {0.2, 0.7, 0.1}};
    const std::vector<Eigen::Vector2d> xy = {{0, 0}, {10, 0}, {0, 20}, {100, 0}, {0, 26}};
    VotingOptions options;  // 1.5, 25 m
    const auto r = spatial_vote(p, xy, options);
    EXPECT_EQ(r.confident, (std::vector<bool>{false, true, true, false, true}));
    EXPECT_EQ(r.species, (std::vector<int>{0, 0, 2, 1, 1}));  // tree 4 (B) is 26 m away from tree 0
    EXPECT_EQ(r.changed, (std::vector<bool>{true, false, false, false, false}));
    options.radius_m = 30;  // now B is a candidate too, and tree 0 finds B most probable
    EXPECT_EQ(spatial_vote(p, xy, options).species[0], 1);
    options.confidence_factor = 4.0;  // 0.8 > 4 x 0.1 but 0.7 < 4 x 0.2: tree 4 is unsure too
    EXPECT_FALSE(spatial_vote(p, xy, options).confident[4]);
    EXPECT_TRUE(spatial_vote(p, xy, options).confident[2]);
    options.confidence_factor = 0.5;
    EXPECT_EQ(test::error_code_of([&] { spatial_vote(p, xy, options); }), ExitCode::Usage);
}

TEST(ClassifyVoting, HelpsGroupedPlantingsMoreThanMixedOnes) {
    EvaluationOptions options;
    options.splits = 20;
    options.voting.radius_m = 25;
    const auto grouped = evaluate(clustered_set(4, 12, 1.4, true, 5), {nearest_mean()}, options).classifiers[0].random_splits;
    const auto mixed = evaluate(clustered_set(4, 12, 1.4, false, 5), {nearest_mean()}, options).classifiers[0].random_splits;
    ASSERT_TRUE(grouped.voted);
    EXPECT_LT(grouped.average_rate, 0.9);  // overlapping classes: the classifier alone errs
    // Measured: 83.5 % -> 86.3 % with voting in groups; mixed plantings gain less or lose.
    EXPECT_GT(grouped.voted_average_rate, grouped.average_rate + 0.02);
    EXPECT_LT(mixed.voted_average_rate - mixed.average_rate, grouped.voted_average_rate - grouped.average_rate);
    // The confident subset is the more accurate one.
    EXPECT_GT(grouped.confident_accuracy, grouped.unconfident_accuracy);
}

TEST(ClassifyReport, WritesTablesHeatMapsAndJson) {
    LabelledSet set = clustered_set(3, 6, 0.8, true, 6);
    for (std::size_t r = 0; r < set.labels.size(); ++r) set.groups.push_back(r % 2 ? "east" : "west");
    EvaluationOptions options;
    options.splits = 4;
    const auto report = evaluate(set, {nearest_mean(), always_first()}, options);
    TempDir dir;
    write_report(report, (dir / "report").string(), R"({"dataset": "test"})");
    for (const char* name : {"summary.json", "per_species.csv", "report.md", "confusion_nearest.csv", "confusion_nearest.png",
                             "confusion_first.csv", "site_confusion_first.csv"})
        EXPECT_TRUE(std::filesystem::exists(dir / "report" / name)) << name;
    const auto summary = nlohmann::json::parse(read_file(dir / "report" / "summary.json"));
    EXPECT_EQ(summary["dataset"], "test");
    EXPECT_EQ(summary["classifiers"]["first"]["random_splits"]["experiments"], 4);
    EXPECT_NEAR(summary["classifiers"]["first"]["random_splits"]["average_recognition_rate"].get<double>(), 1.0 / 3, 1e-12);
    EXPECT_EQ(summary["classifiers"]["nearest"]["site_split"]["experiments"], 2);
    // Confusion CSV: header, one row per species with row percentages summing to 100.
    const std::string csv = read_file(dir / "report" / "confusion_first.csv");
    EXPECT_EQ(csv.substr(0, csv.find('\n')), "true\\predicted,species0,species1,species2,predictions");
    EXPECT_NE(csv.find("\nspecies1,100.0,0.0,0.0,"), std::string::npos);
    const std::string png = read_file(dir / "report" / "confusion_nearest.png");
    EXPECT_EQ(png.substr(1, 3), "PNG");
    // Same inputs, same report files (timings aside, which live in summary.json only).
    TempDir again;
    write_report(report, (again / "report").string());
    EXPECT_EQ(read_file(dir / "report" / "confusion_nearest.png"), read_file(again / "report" / "confusion_nearest.png"));
    EXPECT_EQ(read_file(dir / "report" / "per_species.csv"), read_file(again / "report" / "per_species.csv"));
}

TEST(ClassifyTables, FeatureCsvRoundTripsExactlyAndRejectsBadFiles) {
    FeatureTable t;
    t.feature_names = {"a", "b"};
    const double r0[2] = {0.1, 1.0 / 3}, r1[2] = {-2.5e-300, 123456789.123};
    t.add_row("x/tree_1.las", r0);
    t.add_row("y", r1);
    TempDir dir;
    write_feature_csv(t, dir / "f.csv");
    const auto back = read_feature_csv(dir / "f.csv");
    EXPECT_EQ(back.ids, t.ids);
    EXPECT_EQ(back.values, t.values);
    EXPECT_EQ(back.feature_names, t.feature_names);
    // A missing value (a feature that could not be computed) reads back as NaN; infinity is an error.
    t.add_row("z", std::vector<double>{std::numeric_limits<double>::quiet_NaN(), 2.0});
    write_feature_csv(t, dir / "missing.csv");
    const auto missing = read_feature_csv(dir / "missing.csv");
    EXPECT_TRUE(std::isnan(missing.at(2, 0)));
    EXPECT_EQ(missing.at(2, 1), 2.0);
    test::write_text(dir / "empty_field.csv", "id,a,b\nx,1,\n");
    EXPECT_TRUE(std::isnan(read_feature_csv(dir / "empty_field.csv").at(0, 1)));
    test::write_text(dir / "inf.csv", "id,a,b\nx,1,inf\n");
    try {
        read_feature_csv(dir / "inf.csv");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
    }
    test::write_text(dir / "short.csv", "id,a,b\nx,1\n");
    EXPECT_EQ(test::error_code_of([&] { read_feature_csv(dir / "short.csv"); }), ExitCode::InvalidInput);
    test::write_text(dir / "dup.csv", "id,a,a\nx,1,2\n");
    EXPECT_EQ(test::error_code_of([&] { read_feature_csv(dir / "dup.csv"); }), ExitCode::InvalidInput);
    EXPECT_EQ(test::error_code_of([&] { t.select_columns({"a", "c"}, "f.csv"); }), ExitCode::InvalidInput);
    EXPECT_EQ(t.select_columns({"b", "a"}, "").at(1, 0), 123456789.123);
}

TEST(ClassifyTables, LabelsAcceptTheSynthDatasetTable) {
    TempDir dir;
    test::write_text(dir / "labels.csv",
                     "file,species,species_id,seed,height_m\r\npine/pine_0.las,pine,8,1,9.5\r\noak/oak_0.las,oak,12,2,20\r\n");
    const auto labels = read_labels_csv(dir / "labels.csv");
    ASSERT_EQ(labels.size(), 2u);
    EXPECT_EQ(labels[1].id, "oak/oak_0.las");
    EXPECT_EQ(labels[1].species, "oak");
    EXPECT_FALSE(labels[0].x);
    test::write_text(dir / "truth.csv", "tree_id,species,x,y,tile\n1,pine,10.5,3,a\n");
    const auto truth = read_labels_csv(dir / "truth.csv");
    EXPECT_EQ(*truth[0].x, 10.5);
    EXPECT_EQ(truth[0].group, "a");
    test::write_text(dir / "nospecies.csv", "file,height\na,1\n");
    EXPECT_EQ(test::error_code_of([&] { read_labels_csv(dir / "nospecies.csv"); }), ExitCode::InvalidInput);
    FeatureTable t;
    t.feature_names = {"a"};
    const double v = 1;
    t.add_row("pine/pine_0.las", {&v, 1});
    t.add_row("birch/birch_0.las", {&v, 1});
    EXPECT_EQ(test::error_code_of([&] { labels_for_rows(t, labels, "labels.csv"); }), ExitCode::InvalidInput);
}

TEST(ClassifyBaseline, XGBoostSeesTheSameTablesAndSeparatesClusters) {
    const LabelledSet set = clustered_set(3, 12, 0.3, true, 9);
    XGBoostOptions options;
    options.threads = 1;
    const auto run = xgboost_train_predict(set.features, set.labels, 3, set.features, options);
    ASSERT_EQ(run.probabilities.size(), set.labels.size());
    int correct = 0;
    for (std::size_t r = 0; r < set.labels.size(); ++r) {
        EXPECT_NEAR(run.probabilities[r][0] + run.probabilities[r][1] + run.probabilities[r][2], 1.0, 1e-5);
        correct +=
                std::max_element(run.probabilities[r].begin(), run.probabilities[r].end()) - run.probabilities[r].begin() == set.labels[r];
    }
    EXPECT_EQ(correct, static_cast<int>(set.labels.size()));
    EXPECT_GT(run.rounds, 0);
    EXPECT_EQ(xgboost_version().rfind("xgboost ", 0), 0u);
}

TEST(ClassifyVoting, PlantingLayouts) {
    const std::vector<int> labels = {0, 1, 0, 2, 1, 0};
    const auto grouped = planting_layout(labels, 3, true, 8.0, 1);
    EXPECT_EQ(grouped[0], Eigen::Vector2d(0, 0));
    EXPECT_EQ(grouped[2], Eigen::Vector2d(0, 8));
    EXPECT_EQ(grouped[5], Eigen::Vector2d(0, 16));
    EXPECT_EQ(grouped[4], Eigen::Vector2d(250, 8));
    const auto mixed = planting_layout(labels, 3, false, 8.0, 1);
    EXPECT_EQ(mixed, planting_layout(labels, 3, false, 8.0, 1));
    EXPECT_NE(mixed, planting_layout(labels, 3, false, 8.0, 2));
    std::set<std::pair<double, double>> cells;
    for (const auto& p : mixed) {
        cells.insert({p.x(), p.y()});
        EXPECT_LE(p.x(), 16.0);  // a 3 x 3 grid holds 6 trees
        EXPECT_LE(p.y(), 16.0);
    }
    EXPECT_EQ(cells.size(), labels.size());
}

// Macro-F1, Cohen's kappa and the genus level from the confusion matrix, checked on a classifier
// whose answer is known: always the first species. 3 species x 10 trees, 5 tested per split.
TEST(ClassifyEvaluation, MacroF1KappaAndGenusLevel) {
    LabelledSet set = clustered_set(3, 10, 0.1, false, 7);
    set.class_genus = {"Quercus", "Quercus", "Acer"};
    EvaluationOptions options;
    options.splits = 4;
    const auto report = evaluate(set, {always_first()}, options);
    const Scores& s = report.classifiers[0].random_splits;
    EXPECT_NEAR(s.tree_accuracy, 1.0 / 3, 1e-12);
    // Species 0: precision 1/3, recall 1 -> F1 0.5; the others 0. Kappa of a constant answer: 0.
    EXPECT_NEAR(s.macro_f1, 0.5 / 3, 1e-12);
    EXPECT_NEAR(s.kappa, 0.0, 1e-12);
    ASSERT_TRUE(s.genus_level);
    EXPECT_EQ(s.genera, (std::vector<std::string>{"Acer", "Quercus"}));
    EXPECT_NEAR(s.genus_tree_accuracy, 2.0 / 3, 1e-12);  // both oaks count as right at genus level
    EXPECT_NEAR(s.genus_average_rate, 0.5, 1e-12);       // Quercus 100 %, Acer 0 %
    // A perfect classifier: kappa 1, macro-F1 1.
    const auto perfect = evaluate(set, {nearest_mean()}, options).classifiers[0].random_splits;
    EXPECT_NEAR(perfect.kappa, 1.0, 1e-12);
    EXPECT_NEAR(perfect.macro_f1, 1.0, 1e-12);
    EXPECT_EQ(genus_of("Quercus rubra L."), "Quercus");
    EXPECT_EQ(genus_of("Magnolia sp."), "Magnolia");
    EXPECT_EQ(genus_of(""), "");
}

// Sites that share no species: the site split would test species never trained, so it does not
// run and the report says why; sites that share species get it.
TEST(ClassifyEvaluation, SiteSplitOnlyWhenGroupsShareSpecies) {
    LabelledSet set = clustered_set(4, 6, 0.1, false, 3);
    for (int y : set.labels) set.groups.push_back(y < 2 ? "north" : "south");
    EvaluationOptions options;
    options.splits = 2;
    const auto apart = evaluate(set, {nearest_mean()}, options);
    EXPECT_EQ(apart.classifiers[0].site_split.experiments, 0);
    EXPECT_NE(apart.site_split_note.find("never trained"), std::string::npos) << apart.site_split_note;
    set.groups.clear();
    for (std::size_t r = 0; r < set.labels.size(); ++r) set.groups.push_back((r / 4) % 2 ? "north" : "south");  // every species in both
    const auto shared = evaluate(set, {nearest_mean()}, options);
    EXPECT_EQ(shared.classifiers[0].site_split.experiments, 2);
    EXPECT_TRUE(shared.site_split_note.empty());
}

// --train A --test B: one experiment on exactly the rows given.
TEST(ClassifyEvaluation, TrainOnOneSetTestOnAnother) {
    const LabelledSet set = clustered_set(3, 8, 0.1, false, 5);
    std::vector<std::size_t> train, test;
    for (std::size_t r = 0; r < set.labels.size(); ++r) (r < 12 ? train : test).push_back(r);
    const auto report = evaluate_train_test(set, {nearest_mean()}, train, test, {});
    EXPECT_EQ(report.mode, "train_test");
    const Scores& s = report.classifiers[0].random_splits;
    EXPECT_EQ(s.experiments, 1);
    EXPECT_NEAR(s.tree_accuracy, 1.0, 1e-12);
    int tested = 0;
    for (std::size_t r = 0; r < set.labels.size(); ++r)
        for (int n : s.row_predictions[r]) {
            tested += n;
            EXPECT_TRUE(n == 0 || r >= 12) << "training row " << r << " was tested";
        }
    EXPECT_EQ(tested, 12);
}
