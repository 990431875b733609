#include "classify/evaluation.hpp"

#include "classify/splits.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/random.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <map>
#include <mutex>
#include <set>

#include <tbb/blocked_range.h>

namespace treelobes::classify {

LabelledSet make_labelled_set(const FeatureTable& features, const std::vector<TreeLabel>& labels, const std::string& labels_file) {
    const auto rows = labels_for_rows(features, labels, labels_file);
    LabelledSet set;
    set.features = features;
    std::set<std::string> names;
    for (const auto& l : rows) names.insert(l.species);
    set.classes.assign(names.begin(), names.end());
    bool positions = true, groups = false;
    for (const auto& l : rows) {
        set.labels.push_back(static_cast<int>(std::lower_bound(set.classes.begin(), set.classes.end(), l.species) - set.classes.begin()));
        positions = positions && l.x && l.y;
        groups = groups || !l.group.empty();
    }
    if (positions)
        for (const auto& l : rows) set.positions.emplace_back(*l.x, *l.y);
    if (groups)
        for (const auto& l : rows) set.groups.push_back(l.group);
    std::vector<std::string> genus(set.classes.size());
    bool any_genus = false;
    for (std::size_t r = 0; r < rows.size(); ++r)
        if (genus[set.labels[r]].empty() && !rows[r].scientific_name.empty())
            genus[set.labels[r]] = genus_of(rows[r].scientific_name), any_genus = true;
    if (any_genus) set.class_genus = std::move(genus);
    return set;
}

std::string genus_of(const std::string& scientific_name) {
    const auto begin = scientific_name.find_first_not_of(" \t\"");
    if (begin == std::string::npos) return "";
    const auto end = scientific_name.find_first_of(" \t\"", begin);
    return scientific_name.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
}

std::vector<Eigen::Vector2d> planting_layout(const std::vector<int>& labels, int classes, bool grouped, double spacing_m,
                                             std::uint64_t seed) {
    if (!(spacing_m > 0)) throw Error::usage("planting layout: the spacing must be positive");
    std::vector<Eigen::Vector2d> out(labels.size());
    if (grouped) {
        std::vector<int> planted(classes, 0);
        for (std::size_t i = 0; i < labels.size(); ++i) out[i] = {250.0 * labels[i], spacing_m * planted[labels[i]]++};
        return out;
    }
    std::vector<std::size_t> order(labels.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    Rng rng(stream_seed(seed, 0x1a7047));
    for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng.below(i)]);
    const auto side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(labels.size()))));
    for (std::size_t k = 0; k < order.size(); ++k)
        out[order[k]] = {spacing_m * static_cast<double>(k % side), spacing_m * static_cast<double>(k / side)};
    return out;
}

namespace {

int argmax(const std::vector<double>& p) { return static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin()); }

// Agreement figures of a confusion matrix [true][predicted]: tree accuracy, mean recall over the
// classes that were tested, macro-F1 over those classes and Cohen's kappa.
struct Agreement {
    double accuracy = 0, average_rate = 0, macro_f1 = 0, kappa = 0;
};

Agreement agreement(const std::vector<std::vector<double>>& confusion) {
    const std::size_t k = confusion.size();
    std::vector<double> rows(k, 0), cols(k, 0);
    double total = 0, diagonal = 0;
    for (std::size_t t = 0; t < k; ++t)
        for (std::size_t p = 0; p < k; ++p) rows[t] += confusion[t][p], cols[p] += confusion[t][p], total += confusion[t][p];
    Agreement a;
    if (total <= 0) return a;
    int tested = 0;
    double expected = 0;
    for (std::size_t c = 0; c < k; ++c) {
        diagonal += confusion[c][c];
        expected += rows[c] * cols[c] / (total * total);
        if (rows[c] <= 0) continue;
        ++tested;
        const double recall = confusion[c][c] / rows[c], precision = cols[c] > 0 ? confusion[c][c] / cols[c] : 0.0;
        a.average_rate += recall;
        a.macro_f1 += precision + recall > 0 ? 2 * precision * recall / (precision + recall) : 0.0;
    }
    a.accuracy = diagonal / total;
    a.average_rate /= tested, a.macro_f1 /= tested;
    a.kappa = expected < 1 ? (a.accuracy - expected) / (1 - expected) : 0.0;
    return a;
}

// Macro-F1, kappa and, when the classes have genera, the genus-level figures of `s`.
void add_agreement(Scores& s, const std::vector<std::string>& class_genus) {
    const Agreement species = agreement(s.confusion);
    s.macro_f1 = species.macro_f1, s.kappa = species.kappa;
    if (class_genus.empty()) return;
    std::set<std::string> distinct(class_genus.begin(), class_genus.end());
    s.genera.assign(distinct.begin(), distinct.end());
    std::vector<std::size_t> index;
    for (const auto& g : class_genus) index.push_back(std::lower_bound(s.genera.begin(), s.genera.end(), g) - s.genera.begin());
    std::vector<std::vector<double>> collapsed(s.genera.size(), std::vector<double>(s.genera.size(), 0.0));
    for (std::size_t t = 0; t < s.confusion.size(); ++t)
        for (std::size_t p = 0; p < s.confusion.size(); ++p) collapsed[index[t]][index[p]] += s.confusion[t][p];
    const Agreement genus = agreement(collapsed);
    s.genus_level = true;
    s.genus_tree_accuracy = genus.accuracy, s.genus_average_rate = genus.average_rate;
    s.genus_macro_f1 = genus.macro_f1, s.genus_kappa = genus.kappa;
}

// Empty when every group shares species with the others (enough for a site split), else why not.
std::string site_split_obstacle(const LabelledSet& set, const std::vector<std::string>& groups, double min_shared) {
    for (const auto& g : groups) {
        std::set<int> elsewhere;
        for (std::size_t r = 0; r < set.labels.size(); ++r)
            if (set.groups[r] != g) elsewhere.insert(set.labels[r]);
        std::size_t trees = 0, shared = 0;
        for (std::size_t r = 0; r < set.labels.size(); ++r)
            if (set.groups[r] == g) ++trees, shared += elsewhere.count(set.labels[r]);
        const double share = trees ? static_cast<double>(shared) / static_cast<double>(trees) : 0.0;
        if (share < min_shared) {
            char text[256];
            std::snprintf(text, sizeof(text),
                          "not run: only %.0f %% of the trees of group '%s' are of species that the other groups have (needs %.0f %%); "
                          "a site split would test species never trained",
                          100 * share, g.c_str(), 100 * min_shared);
            return text;
        }
    }
    return "";
}

// Accumulates the scores of one classifier over experiments.
class ScoreAccumulator {
public:
    ScoreAccumulator(int classes, std::size_t rows)
            : classes_(classes),
              rate_sum_(classes, 0),
              rate_count_(classes, 0),
              voted_sum_(classes, 0),
              confusion_(classes, std::vector<double>(classes, 0)),
              row_predictions_(rows, std::vector<int>(classes, 0)) {}

    void add(const std::vector<std::size_t>& rows, const std::vector<int>& truth, const std::vector<int>& predicted,
             const std::vector<bool>& confident, const std::vector<int>* voted, const ClassifierRun& run) {
        std::vector<int> total(classes_, 0), correct(classes_, 0), voted_correct(classes_, 0);
        for (std::size_t i = 0; i < truth.size(); ++i) {
            ++row_predictions_[rows[i]][predicted[i]];
            ++total[truth[i]];
            const bool ok = predicted[i] == truth[i];
            correct[truth[i]] += ok;
            confusion_[truth[i]][predicted[i]] += 1;
            tree_correct_ += ok, ++tree_total_;
            if (confident[i])
                confident_correct_ += ok, ++confident_total_;
            else
                unconfident_correct_ += ok;
            if (voted) {
                const bool v = (*voted)[i] == truth[i];
                voted_correct[truth[i]] += v;
                voted_tree_correct_ += v;
            }
        }
        for (int c = 0; c < classes_; ++c) {
            if (total[c] == 0) continue;
            rate_sum_[c] += static_cast<double>(correct[c]) / total[c];
            voted_sum_[c] += static_cast<double>(voted_correct[c]) / total[c];
            ++rate_count_[c];
        }
        voted_ = voted != nullptr;
        train_seconds_ += run.train_seconds, predict_seconds_ += run.predict_seconds, rounds_ += run.rounds;
        cpu_seconds_ += run.cpu_seconds;
        ++experiments_;
    }

    Scores scores(const std::vector<int>& labels, const std::vector<int>& train_counts) const {
        Scores s;
        s.experiments = experiments_;
        s.confusion = confusion_;
        s.row_predictions = row_predictions_;
        s.species_trees.assign(classes_, 0);
        for (int y : labels) ++s.species_trees[y];
        s.species_train = train_counts;
        s.species_rate.assign(classes_, 0);
        s.voted_species_rate.assign(classes_, 0);
        int rated = 0;
        for (int c = 0; c < classes_; ++c) {
            if (rate_count_[c] == 0) continue;
            s.species_rate[c] = rate_sum_[c] / rate_count_[c];
            s.voted_species_rate[c] = voted_sum_[c] / rate_count_[c];
            s.average_rate += s.species_rate[c];
            s.voted_average_rate += s.voted_species_rate[c];
            ++rated;
        }
        if (rated > 0) s.average_rate /= rated, s.voted_average_rate /= rated;
        const auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
        s.tree_accuracy = ratio(tree_correct_, tree_total_);
        s.confident_fraction = ratio(confident_total_, tree_total_);
        s.confident_accuracy = ratio(confident_correct_, confident_total_);
        s.unconfident_accuracy = ratio(unconfident_correct_, tree_total_ - confident_total_);
        s.voted = voted_;
        if (!voted_) s.voted_average_rate = 0, s.voted_species_rate.assign(classes_, 0);
        s.voted_tree_accuracy = voted_ ? ratio(voted_tree_correct_, tree_total_) : 0.0;
        s.train_seconds = train_seconds_, s.predict_seconds = predict_seconds_, s.cpu_seconds = cpu_seconds_;
        s.mean_rounds = ratio(rounds_, experiments_);
        return s;
    }

private:
    int classes_;
    std::vector<double> rate_sum_;
    std::vector<int> rate_count_;
    std::vector<double> voted_sum_;
    std::vector<std::vector<double>> confusion_;
    std::vector<std::vector<int>> row_predictions_;
    double tree_correct_ = 0, tree_total_ = 0, confident_correct_ = 0, confident_total_ = 0, unconfident_correct_ = 0;
    double voted_tree_correct_ = 0, train_seconds_ = 0, predict_seconds_ = 0, cpu_seconds_ = 0, rounds_ = 0;
    int experiments_ = 0;
    bool voted_ = false;
};

// Trains on `train` rows and predicts `test` rows. Classes absent from the training rows (a site
// split can leave a species out) are dropped for training and get probability 0.
ClassifierRun run_experiment(const LabelledSet& set, const Classifier& classifier, const std::vector<std::size_t>& train,
                             const std::vector<std::size_t>& test, std::uint64_t seed) {
    const int classes = static_cast<int>(set.classes.size());
    std::vector<int> compact(classes, -1), original;
    for (auto r : train)
        if (compact[set.labels[r]] < 0) compact[set.labels[r]] = 0;
    for (int c = 0; c < classes; ++c)
        if (compact[c] == 0) compact[c] = static_cast<int>(original.size()), original.push_back(c);
    std::vector<int> y;
    for (auto r : train) y.push_back(compact[set.labels[r]]);
    const FeatureTable train_table = set.features.select_rows(train), test_table = set.features.select_rows(test);
    const std::clock_t cpu_start = std::clock();
    ClassifierRun run = classifier(train_table, y, static_cast<int>(original.size()), test_table, seed);
    run.cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    for (auto& p : run.probabilities) {
        std::vector<double> full(classes, 0.0);
        for (std::size_t k = 0; k < original.size(); ++k) full[original[k]] = p[k];
        p = std::move(full);
    }
    return run;
}

void score_experiment(const LabelledSet& set, const std::vector<std::size_t>& test, const ClassifierRun& run,
                      const EvaluationOptions& options, ScoreAccumulator& acc) {
    std::vector<int> truth, predicted;
    std::vector<bool> confident;
    std::vector<Eigen::Vector2d> positions;
    for (std::size_t i = 0; i < test.size(); ++i) {
        truth.push_back(set.labels[test[i]]);
        predicted.push_back(argmax(run.probabilities[i]));
        confident.push_back(is_confident(run.probabilities[i], options.voting.confidence_factor));
        if (!set.positions.empty()) positions.push_back(set.positions[test[i]]);
    }
    if (set.positions.empty()) {
        acc.add(test, truth, predicted, confident, nullptr, run);
        return;
    }
    const VotingResult vote = spatial_vote(run.probabilities, positions, options.voting);
    acc.add(test, truth, predicted, confident, &vote.species, run);
}

}  // namespace

EvaluationReport evaluate(const LabelledSet& set, const std::vector<NamedClassifier>& classifiers, const EvaluationOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    if (options.splits < 1) throw Error::usage("--splits must be at least 1");
    if (!(options.train_fraction > 0 && options.train_fraction < 1)) throw Error::usage("the training fraction must be in (0, 1)");
    const int classes = static_cast<int>(set.classes.size());
    if (classes < 2) throw Error::input("", "evaluation needs at least two species, got " + std::to_string(classes));
    std::vector<int> count(classes, 0);
    for (int y : set.labels) ++count[y];
    for (int c = 0; c < classes; ++c)
        if (count[c] < 2)
            throw Error::input("", "species '" + set.classes[c] + "' has " + std::to_string(count[c]) +
                                           " tree(s); every species needs 2 or more to be trained and tested");

    EvaluationReport report;
    report.classes = set.classes;
    report.tree_ids = set.features.ids;
    report.tree_labels = set.labels;
    report.tree_groups = set.groups;
    std::vector<ScoreAccumulator> random_acc(classifiers.size(), ScoreAccumulator(classes, set.labels.size()));
    std::vector<int> train_counts(classes, 0);
    const auto splits = static_cast<std::size_t>(options.splits);
    std::vector<std::vector<std::size_t>> train(splits), test(splits);
    std::vector<std::uint64_t> seeds(splits);
    for (std::size_t s = 0; s < splits; ++s) {
        seeds[s] = stream_seed(options.seed, static_cast<std::uint64_t>(s));
        stratified_split(set.labels, classes, options.train_fraction, seeds[s], true, train[s], test[s]);
    }
    for (auto r : train.front()) ++train_counts[set.labels[r]];
    // The splits of one classifier run side by side (each one's training is parallel inside too,
    // but a round of 5-fold boosting on 100-200 trees is too short to keep two cores busy): the
    // runs are scored afterwards in split order, so the report does not depend on the threads.
    // Their CPU time is measured for the classifier's splits together and shared out evenly.
    Progress progress("classify evaluate: random splits", splits * classifiers.size());
    std::mutex progress_mutex;
    for (std::size_t k = 0; k < classifiers.size(); ++k) {
        std::vector<ClassifierRun> runs(splits);
        const std::clock_t cpu_start = std::clock();
        treelobes::parallel_for(tbb::blocked_range<std::size_t>(0, splits, 1), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t s = range.begin(); s != range.end(); ++s) {
                runs[s] = run_experiment(set, classifiers[k].run, train[s], test[s], seeds[s]);
                const std::lock_guard<std::mutex> lock(progress_mutex);
                progress.advance();
            }
        });
        const double cpu_per_split = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC / static_cast<double>(splits);
        for (std::size_t s = 0; s < splits; ++s) {
            runs[s].cpu_seconds = cpu_per_split;
            score_experiment(set, test[s], runs[s], options, random_acc[k]);
        }
    }
    progress.finish();

    std::vector<std::string> groups;
    if (options.site_split && !set.groups.empty()) {
        std::set<std::string> distinct(set.groups.begin(), set.groups.end());
        groups.assign(distinct.begin(), distinct.end());
    }
    std::vector<ScoreAccumulator> site_acc(classifiers.size(), ScoreAccumulator(classes, set.labels.size()));
    if (groups.size() >= 2) {
        report.site_split_note = site_split_obstacle(set, groups, options.site_split_min_shared);
        if (!report.site_split_note.empty()) {
            log_info("site split " + report.site_split_note);
            groups.clear();
        }
    }
    if (groups.size() >= 2) {
        report.site_groups = groups;
        Progress site_progress("classify evaluate: site split", groups.size());
        for (std::size_t g = 0; g < groups.size(); ++g) {
            std::vector<std::size_t> site_train, site_test;
            for (std::size_t r = 0; r < set.labels.size(); ++r) (set.groups[r] == groups[g] ? site_test : site_train).push_back(r);
            const std::uint64_t seed = stream_seed(options.seed, 1000000 + g);
            for (std::size_t k = 0; k < classifiers.size(); ++k)
                score_experiment(set, site_test, run_experiment(set, classifiers[k].run, site_train, site_test, seed), options,
                                 site_acc[k]);
            site_progress.advance();
        }
        site_progress.finish();
    }
    for (std::size_t k = 0; k < classifiers.size(); ++k) {
        ClassifierReport r;
        r.name = classifiers[k].name;
        r.random_splits = random_acc[k].scores(set.labels, train_counts);
        add_agreement(r.random_splits, set.class_genus);
        if (groups.size() >= 2) {
            r.site_split = site_acc[k].scores(set.labels, {});
            add_agreement(r.site_split, set.class_genus);
        }
        report.classifiers.push_back(std::move(r));
    }
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

EvaluationReport evaluate_train_test(const LabelledSet& set, const std::vector<NamedClassifier>& classifiers,
                                     const std::vector<std::size_t>& train, const std::vector<std::size_t>& test,
                                     const EvaluationOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const int classes = static_cast<int>(set.classes.size());
    std::set<int> trained;
    for (auto r : train) trained.insert(set.labels[r]);
    if (trained.size() < 2) throw Error::input("", "the training set needs at least two species, got " + std::to_string(trained.size()));
    if (test.empty()) throw Error::input("", "the test set has no labelled tree");
    EvaluationReport report;
    report.mode = "train_test";
    report.classes = set.classes;
    report.tree_ids = set.features.ids;
    report.tree_labels = set.labels;
    report.tree_groups = set.groups;
    std::vector<int> train_counts(classes, 0);
    for (auto r : train) ++train_counts[set.labels[r]];
    for (const auto& classifier : classifiers) {
        ScoreAccumulator acc(classes, set.labels.size());
        score_experiment(set, test, run_experiment(set, classifier.run, train, test, stream_seed(options.seed, 0)), options, acc);
        ClassifierReport r;
        r.name = classifier.name;
        r.random_splits = acc.scores(set.labels, train_counts);
        add_agreement(r.random_splits, set.class_genus);
        report.classifiers.push_back(std::move(r));
    }
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

}  // namespace treelobes::classify
