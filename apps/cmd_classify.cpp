// `treelobes classify features|train|predict|evaluate`: species classification (Livny et al. 2011, §6.1).
//   features  INPUT... --out features.csv      200+ shape features per tree (docs/features.md)
//   train     features.csv --labels labels.csv --out model.jb      JointBoost model file
//   predict   model.jb INPUT...|features.csv [--positions P.csv] [--vote]    species per tree
//   evaluate  DATASET_DIR... --splits 100 --out report/   the paper's protocol, voting, XGBoost
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/summary_values.hpp"
#include "classify/batch.hpp"
#include "classify/evaluation.hpp"
#include "classify/feature_table.hpp"
#include "classify/features.hpp"
#include "classify/jointboost.hpp"
#include "classify/voting.hpp"
#include "classify/xgboost_baseline.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/version.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>

namespace treelobes::cli {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace treelobes::classify;

void print(const json& summary, const GlobalOptions& global, const std::string& human) {
    if (global.json)
        std::cout << summary.dump(2) << "\n";
    else
        std::cout << human;
}

// failures.jsonl beside `out` (DESIGN.md: one JSON object per failure with the reason).
void write_failures(const std::vector<BatchFailure>& failures, const fs::path& out) {
    std::string lines;
    for (const auto& f : failures) lines += json{{"item", f.id}, {"reason", f.reason}}.dump() + "\n";
    write_file_atomically(out.parent_path() / "failures.jsonl", lines);
}

struct FeatureFlags {
    std::string tree_attribute;
    std::string relative_to;
    bool no_skeleton = false;
    FeatureOptions options() const {
        FeatureOptions o;
        o.skeleton = !no_skeleton;
        return o;
    }
};

void add_feature_flags(OptionTable& table, FeatureFlags& f) {
    table.add("--tree-attribute", f.tree_attribute, "Split each input into trees by this per-point attribute (e.g. treeID)");
    table.add("--relative-to", f.relative_to, "Row ids are input paths relative to this folder (as in a dataset's labels.csv)");
    table.add_flag("--no-skeleton", f.no_skeleton, "Skip the skeleton features (zeros; faster)");
}

std::vector<BatchInput> batch_inputs(const std::vector<std::string>& files, const FeatureFlags& f) {
    std::vector<BatchInput> inputs;
    for (const auto& file : files) {
        std::string id = file;
        if (!f.relative_to.empty()) id = fs::path(file).lexically_relative(f.relative_to).generic_string();
        inputs.push_back({file, id, f.tree_attribute});
    }
    return inputs;
}

// "removed before the features: ..." from crown_counts_json.
std::string removed_line(const json& removed) {
    return "  removed before the features: " + std::to_string(removed["ground"].get<long>()) + " ground, " +
           std::to_string(removed["understorey"].get<long>()) + " understorey, " + std::to_string(removed["high_outliers"].get<long>()) +
           " high outliers, " + std::to_string(removed["noise"].get<long>()) + " noise points of " +
           std::to_string(removed["points"].get<long>()) + "; " + std::to_string(removed["trees_without_shape_features"].get<long>()) +
           " trees too small for the shape groups (those features missing)\n";
}

// ---------------------------------------------------------------- features
struct FeaturesCommand {
    std::vector<std::string> inputs;
    std::string out;
    bool list = false;
    FeatureFlags flags;
};

int run_features(const FeaturesCommand& c, const OptionTable& option_table, const GlobalOptions& global) {
    if (c.list) {
        std::cout << features_markdown();
        return 0;
    }
    if (c.inputs.empty() || c.out.empty()) throw Error::usage("classify features: give INPUT... and --out features.csv (or --list)");
    const FeatureBatch batch = compute_feature_batch(batch_inputs(c.inputs, c.flags), c.flags.options());
    if (batch.table.rows() == 0) throw Error::input(c.inputs.front(), "no tree gave features (" + batch.failures.front().reason + ")");
    write_feature_csv(batch.table, c.out);
    if (!batch.failures.empty()) write_failures(batch.failures, fs::absolute(c.out));
    const json summary = {{"command", "classify features"},
                          {"treelobes", kVersion},
                          {"options", option_table.json()},
                          {"trees", batch.table.rows()},
                          {"features", batch.table.cols()},
                          {"failed", batch.failures.size()},
                          {"points", batch.points},
                          {"seconds", batch.seconds},
                          {"feature_seconds_per_tree", batch.feature_seconds / batch.table.rows()},
                          {"cpu_seconds_per_tree", batch.cpu_seconds / batch.table.rows()},
                          {"removed", json::parse(crown_counts_json(batch.crowns))},
                          {"out", c.out}};
    print(summary, global,
          std::to_string(batch.table.rows()) + " trees x " + std::to_string(batch.table.cols()) + " features -> " + c.out +
                  (batch.failures.empty() ? "" : " (" + std::to_string(batch.failures.size()) + " failed, see failures.jsonl)") +
                  format_numbers(" (%.1f s)\n", batch.seconds) + removed_line(summary["removed"]));
    return batch.failures.empty() ? 0 : static_cast<int>(ExitCode::PartialFailure);
}

// ---------------------------------------------------------------- train
struct TrainCommand {
    std::string features;
    std::string labels;
    std::string out;
    JointBoostOptions options;
};

int run_train(const TrainCommand& c, const OptionTable& option_table, const GlobalOptions& global) {
    const FeatureTable table = read_feature_csv(c.features);
    const LabelledSet set = make_labelled_set(table, read_labels_csv(c.labels), c.labels);
    const auto start = std::chrono::steady_clock::now();
    JointBoostReport report;
    const JointBoostModel model = train_jointboost(set.features, set.labels, set.classes, c.options, &report);
    const double seconds = seconds_since(start);
    save_jointboost(model, c.out);
    int correct = 0;
    for (std::size_t r = 0; r < table.rows(); ++r) {
        const auto p = model.probabilities(set.features.row(r));
        correct += std::max_element(p.begin(), p.end()) - p.begin() == set.labels[r];
    }
    const double accuracy = static_cast<double>(correct) / static_cast<double>(table.rows());
    json summary = {{"command", "classify train"},
                    {"treelobes", kVersion},
                    {"options", option_table.json()},
                    {"trees", table.rows()},
                    {"features", table.cols()},
                    {"classes", set.classes},
                    {"rounds", report.rounds},
                    {"rounds_tried", report.rounds_tried},
                    {"temperature", report.temperature},
                    {"training_accuracy", accuracy},
                    {"seconds", seconds},
                    {"out", c.out}};
    std::string routing;
    if (model.routed()) {
        summary["scan_routing"] = {{"feature", model.feature_names[model.route_feature]},
                                   {"threshold", model.route_threshold},
                                   {"sparse_classes", model.parts[0].classes.size()},
                                   {"dense_classes", model.parts[1].classes.size()}};
        routing = "  one model per scan kind: " + model.feature_names[model.route_feature] +
                  format_numbers(" <= %.1f", model.route_threshold) + " (sparse: " + std::to_string(report.parts[0].rounds) +
                  " rounds), above (dense: " + std::to_string(report.parts[1].rounds) + " rounds)\n";
    }
    print(summary, global,
          "JointBoost: " + std::to_string(table.rows()) + " trees, " + std::to_string(set.classes.size()) + " species, " +
                  std::to_string(table.cols()) + " features, " + std::to_string(report.rounds) + " rounds (early stop after " +
                  std::to_string(report.rounds_tried) + format_numbers(", temperature %.2f", report.temperature) + "), training accuracy " +
                  format_numbers("%.1f %%", 100 * accuracy) + " -> " + c.out + format_numbers(" (%.2f s)\n", seconds) + routing);
    return 0;
}

// ---------------------------------------------------------------- predict
struct PredictCommand {
    std::string model;
    std::vector<std::string> inputs;
    std::string positions;
    std::string out;
    bool vote = false;
    VotingOptions voting;
    FeatureFlags flags;
};

bool is_feature_table(const std::vector<std::string>& inputs) {
    return inputs.size() == 1 && fs::path(inputs.front()).extension() == ".csv" && read_file(inputs.front()).rfind("id,", 0) == 0;
}

int run_predict(const PredictCommand& c, const OptionTable& option_table, const GlobalOptions& global) {
    const JointBoostModel model = load_jointboost(c.model);
    FeatureTable table;
    std::vector<Eigen::Vector2d> positions;
    std::vector<BatchFailure> failures;
    if (is_feature_table(c.inputs)) {
        table = read_feature_csv(c.inputs.front());
    } else {
        FeatureBatch batch = compute_feature_batch(batch_inputs(c.inputs, c.flags), c.flags.options());
        table = std::move(batch.table);
        positions = std::move(batch.positions);
        failures = std::move(batch.failures);
    }
    if (table.rows() == 0) throw Error::input(c.inputs.front(), "no tree to classify");
    table = table.select_columns(model.feature_names, c.inputs.front());
    if (!c.positions.empty()) {
        std::map<std::string, Eigen::Vector2d> by_id;
        for (const auto& p : read_positions_csv(c.positions)) by_id[p.id] = {p.x, p.y};
        positions.clear();
        for (const auto& id : table.ids) {
            const auto it = by_id.find(id);
            if (it == by_id.end()) throw Error::input(c.positions, "no position for tree '" + id + "'");
            positions.push_back(it->second);
        }
    }
    if (c.vote && positions.empty())
        throw Error::usage("--vote needs positions: give --positions positions.csv (id,x,y) when predicting from a feature table");
    std::vector<std::vector<double>> p;
    for (std::size_t r = 0; r < table.rows(); ++r) p.push_back(model.probabilities(table.row(r)));
    VotingResult vote;
    if (c.vote) vote = spatial_vote(p, positions, c.voting);

    std::string csv = "id,species,probability,confident";
    if (c.vote) csv += ",voted_species";
    for (const auto& name : model.classes) csv += ",p_" + name;
    csv += "\n";
    json trees = json::array();
    std::map<std::string, int> counts;
    int confident = 0, changed = 0;
    for (std::size_t r = 0; r < table.rows(); ++r) {
        const int best = static_cast<int>(std::max_element(p[r].begin(), p[r].end()) - p[r].begin());
        const bool sure = is_confident(p[r], c.voting.confidence_factor);
        const std::string final_species = model.classes[c.vote ? vote.species[r] : best];
        confident += sure;
        changed += c.vote && vote.changed[r];
        ++counts[final_species];
        csv += table.ids[r] + "," + model.classes[best] + "," + format_numbers("%.4f", p[r][best]) + "," + (sure ? "1" : "0");
        if (c.vote) csv += "," + final_species;
        for (double v : p[r]) csv += "," + format_numbers("%.4f", v);
        csv += "\n";
        trees.push_back({{"id", table.ids[r]}, {"species", final_species}, {"probability", p[r][best]}, {"confident", sure}});
    }
    if (!c.out.empty()) write_file_atomically(c.out, csv);
    if (!failures.empty()) write_failures(failures, fs::absolute(c.out.empty() ? std::string("predictions.csv") : c.out));
    const json summary = {{"command", "classify predict"}, {"treelobes", kVersion},      {"options", option_table.json()}, {"trees", trees},
                          {"confident", confident},        {"changed_by_vote", changed}, {"failed", failures.size()},      {"out", c.out}};
    std::string human;
    if (c.out.empty())
        human = csv;
    else {
        human = std::to_string(table.rows()) + " trees classified (" + std::to_string(confident) + " confident";
        if (c.vote) human += ", " + std::to_string(changed) + " changed by spatial voting";
        human += ") -> " + c.out + "\n";
        for (const auto& [species, n] : counts) human += "  " + species + ": " + std::to_string(n) + "\n";
    }
    print(summary, global, human);
    return failures.empty() ? 0 : static_cast<int>(ExitCode::PartialFailure);
}

// ---------------------------------------------------------------- evaluate
struct EvaluateCommand {
    std::vector<std::string> datasets;
    std::string train_dataset, test_dataset;  // --train / --test: one experiment instead of random splits
    bool no_class_weights = false;
    std::string level = "species";    // or "genus": train and test on genus labels
    std::vector<std::string> groups;  // feature groups the classifiers see (empty: all)
    std::string out;
    std::string features;  // reuse a feature table instead of computing it
    bool no_xgboost = false;
    bool no_site_split = false;
    std::string layout;  // "", "grouped" or "mixed": planting positions for voting
    double spacing = 8.0;
    EvaluationOptions options;
    JointBoostOptions jointboost;
    XGBoostOptions xgboost;
    FeatureFlags flags;
};

// Trees and labels of one dataset folder: a `treelobes synth dataset` (labels.csv naming one
// cloud per tree) or folders of `treelobes synth tile` outputs (tile.las split by treeID,
// truth.csv with species and positions; the folder is the site group).
void discover(const fs::path& dir, const std::string& prefix, std::vector<BatchInput>& inputs, std::vector<TreeLabel>& labels) {
    if (fs::exists(dir / "labels.csv")) {
        for (auto label : read_labels_csv(dir / "labels.csv")) {
            inputs.push_back({dir / label.id, prefix + label.id, ""});
            label.id = prefix + label.id;
            labels.push_back(std::move(label));
        }
        return;
    }
    std::vector<fs::path> tiles;
    if (fs::exists(dir / "truth.csv")) tiles.push_back(dir);
    if (fs::is_directory(dir))
        for (const auto& entry : fs::directory_iterator(dir))
            if (entry.is_directory() && fs::exists(entry.path() / "truth.csv")) tiles.push_back(entry.path());
    std::sort(tiles.begin(), tiles.end());
    if (tiles.empty()) throw Error::input(dir.string(), "neither a dataset (labels.csv) nor tiles (folders with truth.csv and tile.las)");
    for (const auto& tile : tiles) {
        const fs::path cloud = fs::exists(tile / "tile.las") ? tile / "tile.las" : tile / "tile.ply";
        const std::string group = prefix + (tile == dir ? dir.filename().string() : tile.filename().string());
        inputs.push_back({cloud, group, "treeID"});
        for (auto label : read_labels_csv(tile / "truth.csv")) {
            label.id = group + "/" + label.id;
            label.group = group;
            labels.push_back(std::move(label));
        }
    }
}

// The columns of `table` whose catalogue group is one of `groups` (docs/features.md); the scan
// descriptor stays (it routes, it is not a tree feature).
FeatureTable only_groups(const FeatureTable& table, const std::vector<std::string>& groups, const std::string& context) {
    std::map<std::string, std::string> group_of;
    std::set<std::string> known;
    for (const auto& info : feature_catalogue()) group_of[info.name] = info.group, known.insert(info.group);
    for (const auto& g : groups)
        if (!known.count(g)) throw Error::usage("--groups: no feature group '" + g + "' (see docs/features.md)");
    std::vector<std::string> names;
    for (const auto& name : table.feature_names) {
        const auto it = group_of.find(name);
        if (is_scan_descriptor(name) || (it != group_of.end() && std::count(groups.begin(), groups.end(), it->second)))
            names.push_back(name);
    }
    return table.select_columns(names, context);
}

NamedClassifier jointboost_classifier(const JointBoostOptions& base) {
    return {"JointBoost",
            [base](const FeatureTable& train, const std::vector<int>& y, int classes, const FeatureTable& test, std::uint64_t seed) {
                JointBoostOptions o = base;
                o.seed = seed;
                std::vector<std::string> names;
                for (int c = 0; c < classes; ++c) names.push_back(std::to_string(c));
                ClassifierRun run;
                const auto start = std::chrono::steady_clock::now();
                JointBoostReport report;
                const JointBoostModel model = train_jointboost(train, y, names, o, &report);
                const auto trained = std::chrono::steady_clock::now();
                for (std::size_t r = 0; r < test.rows(); ++r) run.probabilities.push_back(model.probabilities(test.row(r)));
                run.train_seconds = std::chrono::duration<double>(trained - start).count();
                run.predict_seconds = seconds_since(trained);
                run.rounds = report.rounds;
                return run;
            }};
}

NamedClassifier xgboost_classifier(const XGBoostOptions& base) {
    return {"XGBoost",
            [base](const FeatureTable& train, const std::vector<int>& y, int classes, const FeatureTable& test, std::uint64_t seed) {
                XGBoostOptions o = base;
                o.seed = seed;
                XGBoostRun x = xgboost_train_predict(train, y, classes, test, o);
                ClassifierRun run;
                run.probabilities = std::move(x.probabilities);
                run.train_seconds = x.train_seconds, run.predict_seconds = x.predict_seconds, run.rounds = x.rounds;
                return run;
            }};
}

int run_evaluate(const EvaluateCommand& c, const OptionTable& option_table, const GlobalOptions& global) {
    const bool transfer = !c.train_dataset.empty() || !c.test_dataset.empty();
    if (transfer && (c.train_dataset.empty() || c.test_dataset.empty() || !c.datasets.empty()))
        throw Error::usage("classify evaluate: give DATASET... (random splits) or both --train DATASET and --test DATASET");
    if (!transfer && c.datasets.empty()) throw Error::usage("classify evaluate: give DATASET... or --train DATASET --test DATASET");
    if (transfer && !c.features.empty()) throw Error::usage("classify evaluate: --features cannot be used with --train/--test");
    std::vector<std::string> datasets = c.datasets;
    if (transfer) datasets = {c.train_dataset, c.test_dataset};
    std::vector<BatchInput> inputs;
    std::vector<TreeLabel> labels;
    // Ids carry the dataset folder's name when there are several folders (train/ and test/ with --train/--test).
    for (std::size_t k = 0; k < datasets.size(); ++k) {
        std::string prefix;
        if (transfer)
            prefix = k == 0 ? "train/" : "test/";
        else if (datasets.size() > 1)
            prefix = fs::path(datasets[k]).lexically_normal().filename().string() + "/";
        discover(datasets[k], prefix, inputs, labels);
    }
    // Dataset folders that are not tiles have no site groups of their own.
    FeatureTable table;
    std::vector<BatchFailure> failures;
    json extra = {{"command", "classify evaluate"}, {"treelobes", kVersion},
                  {"options", option_table.json()}, {"datasets", datasets},
                  {"baseline", xgboost_version()},  {"class_weights", c.no_class_weights ? "none" : "balanced"}};
    if (!c.features.empty()) {
        table = read_feature_csv(c.features);
        extra["features_file"] = c.features;
    } else {
        FeatureBatch batch = compute_feature_batch(inputs, c.flags.options());
        if (batch.table.rows() == 0) throw Error::input(datasets.front(), "no tree gave features");
        const std::string crowns = crown_counts_csv(batch);
        table = std::move(batch.table);
        failures = std::move(batch.failures);
        fs::create_directories(c.out);
        write_feature_csv(table, fs::path(c.out) / "features.csv");
        extra["feature_seconds_per_tree"] = batch.feature_seconds / static_cast<double>(table.rows());
        extra["feature_seconds_total"] = batch.seconds;
        extra["feature_cpu_seconds_per_tree"] = batch.cpu_seconds / static_cast<double>(table.rows());
        extra["points"] = batch.points;
        extra["removed"] = json::parse(crown_counts_json(batch.crowns));
        write_file_atomically(fs::path(c.out) / "crowns.csv", crowns);
    }
    if (c.level == "genus")
        for (auto& l : labels) {
            if (l.scientific_name.empty())
                throw Error::input(datasets.front(),
                                   "--level genus needs a scientific_name (or genus) column in labels.csv; tree '" + l.id + "' has none");
            l.species = genus_of(l.scientific_name);
        }
    extra["level"] = c.level;
    if (!c.groups.empty()) {
        table = only_groups(table, c.groups, datasets.front());
        extra["feature_groups"] = c.groups;
    }
    // Only labelled trees that gave features take part.
    std::set<std::string> have(table.ids.begin(), table.ids.end());
    std::vector<TreeLabel> used;
    for (const auto& l : labels)
        if (have.count(l.id)) used.push_back(l);
    std::vector<std::size_t> rows;
    std::set<std::string> labelled;
    for (const auto& l : used) labelled.insert(l.id);
    for (std::size_t r = 0; r < table.rows(); ++r)
        if (labelled.count(table.ids[r])) rows.push_back(r);
    table = table.select_rows(rows);
    LabelledSet set = make_labelled_set(table, used, datasets.front());
    if (!c.layout.empty()) {
        set.positions = planting_layout(set.labels, static_cast<int>(set.classes.size()), c.layout == "grouped", c.spacing, c.options.seed);
        extra["layout"] = {{"planting", c.layout}, {"spacing_m", c.spacing}};
    }

    JointBoostOptions jointboost = c.jointboost;
    XGBoostOptions xgboost = c.xgboost;
    jointboost.balance_classes = xgboost.balance_classes = !c.no_class_weights;
    std::vector<NamedClassifier> classifiers = {jointboost_classifier(jointboost)};
    if (!c.no_xgboost) classifiers.push_back(xgboost_classifier(xgboost));
    EvaluationOptions options = c.options;
    options.site_split = !c.no_site_split;
    EvaluationReport report;
    if (transfer) {
        std::vector<std::size_t> train_rows, test_rows;
        for (std::size_t r = 0; r < set.features.rows(); ++r)
            (set.features.ids[r].rfind("train/", 0) == 0 ? train_rows : test_rows).push_back(r);
        report = evaluate_train_test(set, classifiers, train_rows, test_rows, options);
        std::set<std::string> trained, untrained;
        for (auto r : train_rows) trained.insert(set.classes[set.labels[r]]);
        for (auto r : test_rows)
            if (!trained.count(set.classes[set.labels[r]])) untrained.insert(set.classes[set.labels[r]]);
        extra["test_species_not_trained"] = untrained;
        if (!untrained.empty())
            log_warn("species of the test set that the training set lacks (always wrong): " + std::to_string(untrained.size()));
    } else {
        report = evaluate(set, classifiers, options);
    }
    extra["trees"] = set.labels.size();
    extra["failed"] = failures.size();
    write_report(report, c.out, extra.dump());
    if (!failures.empty()) write_failures(failures, fs::path(c.out) / "features.csv");
    json summary = json::parse(read_file(fs::path(c.out) / "summary.json"));
    print(summary, global,
          report_summary(report) + (extra.contains("removed") ? "\n" + removed_line(extra["removed"]) : std::string()) + "\nreport -> " +
                  c.out + "\n");
    return failures.empty() ? 0 : static_cast<int>(ExitCode::PartialFailure);
}

}  // namespace

void add_classify_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    CLI::App* classify =
            app.add_subcommand("classify", "Species classification: features, JointBoost, evaluation (Livny et al. 2011, §6.1)");
    classify->require_subcommand(1);

    auto features = std::make_shared<FeaturesCommand>();
    CLI::App* f = classify->add_subcommand("features", "Shape features of tree point clouds -> features.csv");
    auto features_table = std::make_shared<OptionTable>(f);
    f->add_option("inputs", features->inputs, "Point clouds, one tree each (or many with --tree-attribute)");
    features_table->add("--out,-o", features->out, "Output CSV");
    features_table->add_flag("--list", features->list, "Print the feature catalogue (docs/features.md) and exit");
    add_feature_flags(*features_table, features->flags);
    f->callback([features, features_table, &global, &job] {
        job = [features, features_table, &global] { return run_features(*features, *features_table, global); };
    });

    auto train = std::make_shared<TrainCommand>();
    CLI::App* t = classify->add_subcommand("train", "Train a JointBoost model from features.csv and labels.csv");
    auto train_table = std::make_shared<OptionTable>(t);
    t->add_option("features", train->features, "Feature table from `classify features`")->required();
    train_table->add("--labels", train->labels, "CSV with id and species columns")->required();
    train_table->add("--out,-o", train->out, "Model file")->required();
    train_table->add("--max-rounds", train->options.max_rounds, "Maximum boosting rounds")->check(CLI::Range(1, 100000));
    train_table->add("--folds", train->options.folds, "Cross-validation folds for early stopping and calibration (0 = off)")
            ->check(CLI::Range(0, 20));
    train_table->add("--patience", train->options.patience, "Rounds without improvement before stopping")->check(cli::NonNegativeNumber);
    train_table->add("--seed", train->options.seed, "Seed of the cross-validation folds");
    train_table->add_flag("--no-calibration{false}", train->options.calibrate,
                          "Keep the probability temperature at 1 instead of fitting it out of fold");
    train_table->add_flag("--no-scan-routing{false}", train->options.route_by_scan,
                          "One model for all trees instead of one per scan kind (told apart by scan_point_density)");
    train_table->add_flag("--refit{false}", train->options.fold_ensemble,
                          "Boost the final model again on all training trees instead of averaging the cross-validation runs");
    train_table->add_flag("--average-scores{false}", train->options.average_probabilities,
                          "The fold ensemble averages its members' scores H instead of their probabilities");
    train_table->add_flag("--no-class-weights{false}", train->options.balance_classes,
                          "Every tree weighs 1 (default: N / (K n_species), so that rare species count as much as common ones)");
    t->callback([train, train_table, &global, &job] {
        job = [train, train_table, &global] { return run_train(*train, *train_table, global); };
    });

    auto predict = std::make_shared<PredictCommand>();
    CLI::App* p = classify->add_subcommand("predict", "Species of trees (point clouds or a feature table), optional spatial voting");
    auto predict_table = std::make_shared<OptionTable>(p);
    p->add_option("model", predict->model, "Model file from `classify train`")->required();
    p->add_option("inputs", predict->inputs, "Point clouds or one features.csv")->required();
    predict_table->add("--positions", predict->positions, "CSV with id, x, y (default for clouds: the mean of their points)");
    predict_table->add_flag("--vote", predict->vote, "Spatial voting among the trees given");
    predict_table->add("--confidence", predict->voting.confidence_factor, "Confident when h1 > factor * h2")->check(CLI::Range(1.0, 100.0));
    predict_table->add("--radius", predict->voting.radius_m, "Voting neighbourhood, m")->check(cli::NonNegativeNumber);
    predict_table->add("--out,-o", predict->out, "predictions.csv (default: print the table)");
    add_feature_flags(*predict_table, predict->flags);
    p->callback([predict, predict_table, &global, &job] {
        job = [predict, predict_table, &global] { return run_predict(*predict, *predict_table, global); };
    });

    auto evaluate = std::make_shared<EvaluateCommand>();
    CLI::App* e = classify->add_subcommand("evaluate", "The paper's protocol (50/50 splits), site split, voting, XGBoost baseline");
    auto evaluate_table = std::make_shared<OptionTable>(e);
    e->add_option("datasets", evaluate->datasets, "`synth dataset` folders (labels.csv) or folders of `synth tile` outputs");
    evaluate_table->add("--train", evaluate->train_dataset, "Train on this dataset folder (with --test: one experiment, no random splits)");
    evaluate_table->add("--test", evaluate->test_dataset, "Test on this dataset folder (with --train)");
    evaluate_table
            ->add("--groups", evaluate->groups,
                  "Feature groups the classifiers see (default all; e.g. --groups airborne for sparse airborne crowns)")
            ->delimiter(',');
    evaluate_table->add("--train-fraction", evaluate->options.train_fraction, "Share of each species that trains in a random split")
            ->check(CLI::Range(0.05, 0.95));
    evaluate_table
            ->add("--level", evaluate->level,
                  "Classes to train and test: species, or genus (the first word of labels.csv's scientific_name)")
            ->check(CLI::IsMember({"species", "genus"}));
    evaluate_table->add_flag("--no-class-weights", evaluate->no_class_weights,
                             "Every tree weighs 1 (default: N / (K n_species), so that rare species count as much as common ones)");
    evaluate_table->add("--out,-o", evaluate->out, "Report folder")->required();
    evaluate_table->add("--splits", evaluate->options.splits, "Random 50/50 splits")->check(CLI::Range(1, 100000));
    evaluate_table->add("--seed", evaluate->options.seed, "Seed of the splits");
    evaluate_table->add("--features", evaluate->features, "Reuse a feature table (e.g. report/features.csv of an earlier run)");
    evaluate_table->add("--confidence", evaluate->options.voting.confidence_factor, "Confident when h1 > factor * h2")
            ->check(CLI::Range(1.0, 100.0));
    evaluate_table->add("--radius", evaluate->options.voting.radius_m, "Voting neighbourhood, m")->check(cli::NonNegativeNumber);
    evaluate_table->add("--max-rounds", evaluate->jointboost.max_rounds, "JointBoost maximum rounds")->check(CLI::Range(1, 100000));
    evaluate_table
            ->add("--folds", evaluate->jointboost.folds,
                  "JointBoost: cross-validation folds on the training half for early stopping and calibration (0 = off)")
            ->check(CLI::Range(0, 20));
    evaluate_table->add("--patience", evaluate->jointboost.patience, "JointBoost: rounds without improvement before stopping")
            ->check(cli::NonNegativeNumber);
    evaluate_table->add_flag("--no-calibration{false}", evaluate->jointboost.calibrate,
                             "JointBoost: keep the probability temperature at 1 instead of fitting it out of fold");
    evaluate_table->add_flag("--no-scan-routing{false}", evaluate->jointboost.route_by_scan,
                             "JointBoost: one model for all trees instead of one per scan kind (told apart by scan_point_density)");
    evaluate_table
            ->add("--settled-logloss", evaluate->jointboost.settled_logloss,
                  "JointBoost: stop when every out-of-fold tree is right at a mean log-loss below this (0 = off)")
            ->check(cli::NonNegativeNumber);
    evaluate_table->add_flag(
            "--refit{false}", evaluate->jointboost.fold_ensemble,
            "JointBoost: boost the final model again on all training trees instead of averaging the cross-validation runs");
    evaluate_table->add_flag("--average-scores{false}", evaluate->jointboost.average_probabilities,
                             "JointBoost: the fold ensemble averages its members' scores H instead of their probabilities");
    evaluate_table
            ->add("--layout", evaluate->layout,
                  "Plant the trees for spatial voting: grouped (one street per species) or mixed (random grid); "
                  "replaces the dataset's positions")
            ->check(CLI::IsMember({"grouped", "mixed"}));
    evaluate_table->add("--spacing", evaluate->spacing, "Distance between planted trees, m (with --layout)")->check(cli::PositiveNumber);
    evaluate_table->add_flag("--no-xgboost", evaluate->no_xgboost, "Skip the XGBoost baseline");
    evaluate_table->add_flag("--no-site-split", evaluate->no_site_split, "Skip the leave-one-site-out split");
    add_feature_flags(*evaluate_table, evaluate->flags);
    e->callback([evaluate, evaluate_table, &global, &job] {
        job = [evaluate, evaluate_table, &global] { return run_evaluate(*evaluate, *evaluate_table, global); };
    });
}

}  // namespace treelobes::cli
