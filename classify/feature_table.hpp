// FeatureTable: one row of named features per tree, and the CSV files that carry them between
// `classify features`, `classify train`, `classify predict` and `classify evaluate`.
//
// features.csv: a header `id,<feature>,<feature>,...` then one line per tree; values are written
// in the shortest form that reads back to the same double, so a table round-trips exactly.
// labels.csv:   a header naming at least an id column (`id`, `tree`, `tree_id` or `file`) and a
// species column (`species`, `label` or `class`); optional `x`,`y` (metres, for spatial voting)
// and a group column (`tile`, `site`, `group` or `plot`, for the split by site). Other columns
// are ignored, so a synth truth table can be passed as it is.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace treelobes::classify {

struct FeatureTable {
    std::vector<std::string> feature_names;
    std::vector<std::string> ids;  // one per row
    std::vector<double> values;    // row-major, rows() x cols()

    std::size_t rows() const { return ids.size(); }
    std::size_t cols() const { return feature_names.size(); }
    const double* row(std::size_t r) const { return values.data() + r * cols(); }
    double at(std::size_t r, std::size_t c) const { return values[r * cols() + c]; }

    // Appends a row; throws Error(Internal) when its length differs from cols().
    void add_row(const std::string& id, std::span<const double> row);
    // The rows at `indices`, in that order.
    FeatureTable select_rows(const std::vector<std::size_t>& indices) const;
    // The columns named `names`, in that order; throws Error::input(context, ...) naming the
    // first missing feature (a model trained on other features).
    FeatureTable select_columns(const std::vector<std::string>& names, const std::string& context) const;
    // Row index of an id; nullopt when absent.
    std::optional<std::size_t> find(const std::string& id) const;
};

FeatureTable read_feature_csv(const std::filesystem::path& path);
void write_feature_csv(const FeatureTable& table, const std::filesystem::path& path);

struct TreeLabel {
    std::string id;
    std::string species;
    std::optional<double> x, y;   // position, metres (spatial voting)
    std::string group;            // site or tile ("" when the file has none)
    std::string scientific_name;  // optional column `scientific_name` (or `genus`): its first word is the genus
};

std::vector<TreeLabel> read_labels_csv(const std::filesystem::path& path);

struct TreePosition {
    std::string id;
    double x = 0, y = 0;
};
// A CSV with an id column and x, y columns (the labels aliases apply); other columns ignored.
std::vector<TreePosition> read_positions_csv(const std::filesystem::path& path);

// Labels in the order of the table's rows; throws Error::input naming the first row whose id
// has no label.
std::vector<TreeLabel> labels_for_rows(const FeatureTable& table, const std::vector<TreeLabel>& labels, const std::string& labels_file);

// Splits one CSV line at commas (no quoting: ids and names never contain commas). Trims spaces
// and a trailing '\r'.
std::vector<std::string> split_csv_line(const std::string& line);

}  // namespace treelobes::classify
