// Writing the evaluation report: JSON summary, CSV tables, confusion heat maps (PNG) and a
// Markdown page. The heat map is labelled with render/text.hpp: the labels are what makes a
// confusion matrix readable.
#include "classify/evaluation.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "render/image.hpp"
#include "render/text.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

namespace treelobes::classify {

namespace {

using nlohmann::json;

using render::draw_text;
using render::text_width;

std::vector<std::vector<double>> row_percentages(const std::vector<std::vector<double>>& counts) {
    auto out = counts;
    for (auto& row : out) {
        double total = 0;
        for (double v : row) total += v;
        for (double& v : row) v = total > 0 ? 100.0 * v / total : 0.0;
    }
    return out;
}

// Rows: true species, columns: predicted (numbered like the rows); white (0 %) to dark blue (100 %).
void write_heatmap(const std::vector<std::vector<double>>& percent, const std::vector<std::string>& classes, const std::string& title,
                   const std::filesystem::path& path) {
    const int n = static_cast<int>(classes.size()), cell = 40, scale = 2, margin = 12;
    int label_width = 0;
    for (int c = 0; c < n; ++c) label_width = std::max(label_width, text_width(std::to_string(c + 1) + " " + classes[c], scale));
    const int left = margin + label_width + 8, top = margin + 5 * scale + 14 + 5 * scale + 8;
    const int width = std::max(left + n * cell + margin, margin + text_width(title, scale) + margin);
    render::Image image(width, top + n * cell + margin + 5 * scale + 10, {255, 255, 255, 255});
    draw_text(image, margin, margin, title, scale, {0, 0, 0, 255});
    for (int c = 0; c < n; ++c) {
        const std::string number = std::to_string(c + 1);
        draw_text(image, left + c * cell + (cell - text_width(number, scale)) / 2, top - 5 * scale - 6, number, scale, {0, 0, 0, 255});
        draw_text(image, margin, top + c * cell + (cell - 5 * scale) / 2, number + " " + classes[c], scale, {0, 0, 0, 255});
    }
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) {
            const double v = std::clamp(percent[r][c] / 100.0, 0.0, 1.0);
            const auto shade = [&](double white, double full) { return static_cast<std::uint8_t>(white + (full - white) * v); };
            const render::Rgba colour{shade(255, 8), shade(255, 48), shade(255, 107), 255};
            image.fill_rect(left + c * cell + 1, top + r * cell + 1, left + (c + 1) * cell, top + (r + 1) * cell, colour);
            if (percent[r][c] >= 0.5) {
                char text[16];
                std::snprintf(text, sizeof text, "%.0f", percent[r][c]);
                const render::Rgba ink = v > 0.5 ? render::Rgba{255, 255, 255, 255} : render::Rgba{0, 0, 0, 255};
                draw_text(image, left + c * cell + (cell - text_width(text, scale)) / 2, top + r * cell + (cell - 5 * scale) / 2, text,
                          scale, ink);
            }
        }
    draw_text(image, left, top + n * cell + 6, "ROWS: TRUE SPECIES  COLUMNS: PREDICTED  (% OF ROW)", 1, {80, 80, 80, 255});
    render::write_png(image, path);
}

std::string percent(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f", 100 * v);
    return text;
}

void write_confusion_csv(const std::vector<std::vector<double>>& counts, const std::vector<std::string>& classes,
                         const std::filesystem::path& path) {
    const auto p = row_percentages(counts);
    std::ostringstream out;
    out << "true\\predicted";
    for (const auto& c : classes) out << ',' << c;
    out << ",predictions\n";
    for (std::size_t r = 0; r < classes.size(); ++r) {
        out << classes[r];
        double total = 0;
        for (std::size_t c = 0; c < classes.size(); ++c) {
            char text[32];
            std::snprintf(text, sizeof text, "%.1f", p[r][c]);
            out << ',' << text;
            total += counts[r][c];
        }
        out << ',' << static_cast<long>(total) << '\n';
    }
    write_file_atomically(path, out.str());
}

json scores_json(const Scores& s, const std::vector<std::string>& classes) {
    json species = json::object(), voted = json::object();
    for (std::size_t c = 0; c < classes.size(); ++c) {
        species[classes[c]] = s.species_rate[c];
        if (s.voted) voted[classes[c]] = s.voted_species_rate[c];
    }
    json j = {{"experiments", s.experiments},
              {"average_recognition_rate", s.average_rate},
              {"tree_accuracy", s.tree_accuracy},
              {"species_rate", species},
              {"confident_fraction", s.confident_fraction},
              {"confident_accuracy", s.confident_accuracy},
              {"unconfident_accuracy", s.unconfident_accuracy},
              {"train_seconds_total", s.train_seconds},
              {"train_seconds_mean", s.experiments ? s.train_seconds / s.experiments : 0.0},
              {"cpu_seconds_mean", s.experiments ? s.cpu_seconds / s.experiments : 0.0},
              {"predict_seconds_total", s.predict_seconds},
              {"mean_rounds", s.mean_rounds},
              {"macro_f1", s.macro_f1},
              {"kappa", s.kappa}};
    if (s.genus_level)
        j["genus"] = {{"genera", s.genera},
                      {"tree_accuracy", s.genus_tree_accuracy},
                      {"average_recognition_rate", s.genus_average_rate},
                      {"macro_f1", s.genus_macro_f1},
                      {"kappa", s.genus_kappa}};
    if (s.voted) {
        j["voted_average_recognition_rate"] = s.voted_average_rate;
        j["voted_tree_accuracy"] = s.voted_tree_accuracy;
        j["voted_species_rate"] = voted;
    }
    return j;
}

std::string safe_name(std::string name) {
    for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    return name;
}

}  // namespace

namespace {

// Random-split accuracy of the test predictions of each group's trees (e.g. per scanner).
json group_accuracy(const EvaluationReport& report, const Scores& scores) {
    std::map<std::string, std::pair<double, double>> counts;  // group -> (correct, tested)
    for (std::size_t r = 0; r < report.tree_groups.size() && r < scores.row_predictions.size(); ++r) {
        auto& [correct, tested] = counts[report.tree_groups[r]];
        for (std::size_t c = 0; c < scores.row_predictions[r].size(); ++c) {
            tested += scores.row_predictions[r][c];
            if (static_cast<int>(c) == report.tree_labels[r]) correct += scores.row_predictions[r][c];
        }
    }
    json out = json::object();
    for (const auto& [group, n] : counts) out[group] = n.second > 0 ? n.first / n.second : 0.0;
    return out;
}

// One line per tree: how often it was tested and predicted right, and its most frequent error.
void write_per_tree_csv(const EvaluationReport& report, const Scores& scores, const std::filesystem::path& path) {
    std::ostringstream csv;
    csv << "id,species,group,tested,correct,rate,most_frequent_error\n";
    for (std::size_t r = 0; r < report.tree_ids.size() && r < scores.row_predictions.size(); ++r) {
        const auto& counts = scores.row_predictions[r];
        const int truth = report.tree_labels[r];
        int tested = 0, wrong_best = -1;
        for (std::size_t c = 0; c < counts.size(); ++c) {
            tested += counts[c];
            if (static_cast<int>(c) != truth && counts[c] > 0 && (wrong_best < 0 || counts[c] > counts[wrong_best]))
                wrong_best = static_cast<int>(c);
        }
        csv << report.tree_ids[r] << ',' << report.classes[truth] << ',' << (report.tree_groups.empty() ? "" : report.tree_groups[r]) << ','
            << tested << ',' << counts[truth] << ',' << (tested > 0 ? percent(counts[truth] / static_cast<double>(tested)) : "") << ','
            << (wrong_best < 0 ? "" : report.classes[wrong_best]) << '\n';
    }
    write_file_atomically(path, csv.str());
}

}  // namespace

void write_report(const EvaluationReport& report, const std::string& directory, const std::string& extra_json) {
    const std::filesystem::path dir(directory);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw Error::input(directory, "cannot create the report folder (" + ec.message() + ")");
    json summary = json::parse(extra_json);
    summary["classes"] = report.classes;
    summary["site_groups"] = report.site_groups;
    summary["mode"] = report.mode;
    if (!report.site_split_note.empty()) summary["site_split_note"] = report.site_split_note;
    summary["seconds"] = report.seconds;
    for (const auto& c : report.classifiers) {
        json entry = {{"random_splits", scores_json(c.random_splits, report.classes)}};
        if (!report.tree_groups.empty()) entry["random_splits"]["group_accuracy"] = group_accuracy(report, c.random_splits);
        if (c.site_split.experiments > 0) entry["site_split"] = scores_json(c.site_split, report.classes);
        summary["classifiers"][c.name] = entry;
        const std::string stem = safe_name(c.name);
        write_confusion_csv(c.random_splits.confusion, report.classes, dir / ("confusion_" + stem + ".csv"));
        write_heatmap(
                row_percentages(c.random_splits.confusion), report.classes,
                c.name + " " + std::to_string(c.random_splits.experiments) + " SPLITS: " + percent(c.random_splits.average_rate) + " %",
                dir / ("confusion_" + stem + ".png"));
        if (c.site_split.experiments > 0)
            write_confusion_csv(c.site_split.confusion, report.classes, dir / ("site_confusion_" + stem + ".csv"));
        write_per_tree_csv(report, c.random_splits, dir / ("per_tree_" + stem + ".csv"));
    }
    write_file_atomically(dir / "summary.json", summary.dump(2) + "\n");

    std::ostringstream csv;
    csv << "species,trees,train_per_split";
    for (const auto& c : report.classifiers) {
        csv << ',' << safe_name(c.name) << "_rate";
        if (c.random_splits.voted) csv << ',' << safe_name(c.name) << "_voted_rate";
        if (c.site_split.experiments > 0) csv << ',' << safe_name(c.name) << "_site_rate";
    }
    csv << '\n';
    for (std::size_t k = 0; k < report.classes.size(); ++k) {
        const auto& first = report.classifiers.front().random_splits;
        csv << report.classes[k] << ',' << first.species_trees[k] << ',' << first.species_train[k];
        for (const auto& c : report.classifiers) {
            csv << ',' << percent(c.random_splits.species_rate[k]);
            if (c.random_splits.voted) csv << ',' << percent(c.random_splits.voted_species_rate[k]);
            if (c.site_split.experiments > 0) csv << ',' << percent(c.site_split.species_rate[k]);
        }
        csv << '\n';
    }
    write_file_atomically(dir / "per_species.csv", csv.str());
    write_file_atomically(dir / "report.md", report_summary(report));
}

std::string report_summary(const EvaluationReport& report) {
    std::ostringstream out;
    out << "Species classification: " << report.classes.size() << " species, ";
    if (report.mode == "train_test")
        out << "trained on one set, tested on another";
    else
        out << (report.classifiers.empty() ? 0 : report.classifiers.front().random_splits.experiments) << " random 50/50 splits";
    if (!report.site_groups.empty()) out << ", site split over " << report.site_groups.size() << " groups";
    char line[256];
    std::snprintf(line, sizeof line, " (%.1f s)\n", report.seconds);
    out << line;
    if (!report.site_split_note.empty()) out << "Site split " << report.site_split_note << "\n";
    out << "\n| classifier | average recognition rate | tree accuracy | macro-F1 | kappa | genus: tree accuracy / rate | confident: share "
           "/ accuracy | unconfident accuracy | with voting: rate / trees | site split | train s/split | CPU s/split |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& c : report.classifiers) {
        const Scores& s = c.random_splits;
        std::snprintf(line, sizeof line, "%.3f | %.3f", s.macro_f1, s.kappa);
        out << "| " << c.name << " | " << percent(s.average_rate) << " % | " << percent(s.tree_accuracy) << " % | " << line << " | "
            << (s.genus_level ? percent(s.genus_tree_accuracy) + " % / " + percent(s.genus_average_rate) + " %" : std::string("-")) << " | "
            << percent(s.confident_fraction) << " % / " << percent(s.confident_accuracy) << " % | " << percent(s.unconfident_accuracy)
            << " % | " << (s.voted ? percent(s.voted_average_rate) + " % / " + percent(s.voted_tree_accuracy) + " %" : std::string("-"))
            << " | " << (c.site_split.experiments > 0 ? percent(c.site_split.average_rate) + " %" : std::string("-")) << " | ";
        std::snprintf(line, sizeof line, "%.3f | %.3f", s.experiments ? s.train_seconds / s.experiments : 0.0,
                      s.experiments ? s.cpu_seconds / s.experiments : 0.0);
        out << line << " |\n";
    }
    out << "\n| species | trees |";
    for (const auto& c : report.classifiers) out << ' ' << c.name << " |";
    out << "\n|---|---|";
    for (std::size_t k = 0; k < report.classifiers.size(); ++k) out << "---|";
    out << '\n';
    for (std::size_t k = 0; k < report.classes.size(); ++k) {
        out << "| " << report.classes[k] << " | " << report.classifiers.front().random_splits.species_trees[k] << " |";
        for (const auto& c : report.classifiers) out << ' ' << percent(c.random_splits.species_rate[k]) << " % |";
        out << '\n';
    }
    return out.str();
}

}  // namespace treelobes::classify
