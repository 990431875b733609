#include "classify/feature_table.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <limits>
#include <sstream>
#include <unordered_map>

namespace treelobes::classify {

void FeatureTable::add_row(const std::string& id, std::span<const double> row) {
    if (row.size() != cols())
        throw Error(ExitCode::Internal, "feature row '" + id + "' has " + std::to_string(row.size()) + " values, the table has " +
                                                std::to_string(cols()) + " features");
    ids.push_back(id);
    values.insert(values.end(), row.begin(), row.end());
}

FeatureTable FeatureTable::select_rows(const std::vector<std::size_t>& indices) const {
    FeatureTable out;
    out.feature_names = feature_names;
    out.ids.reserve(indices.size());
    out.values.reserve(indices.size() * cols());
    for (std::size_t r : indices) out.add_row(ids[r], {row(r), cols()});
    return out;
}

FeatureTable FeatureTable::select_columns(const std::vector<std::string>& names, const std::string& context) const {
    std::unordered_map<std::string, std::size_t> index;
    for (std::size_t c = 0; c < cols(); ++c) index.emplace(feature_names[c], c);
    std::vector<std::size_t> source;
    for (const auto& name : names) {
        const auto it = index.find(name);
        if (it == index.end()) throw Error::input(context, "feature '" + name + "' is missing (the model was trained on it)");
        source.push_back(it->second);
    }
    FeatureTable out;
    out.feature_names = names;
    out.ids = ids;
    out.values.resize(rows() * names.size());
    for (std::size_t r = 0; r < rows(); ++r)
        for (std::size_t c = 0; c < names.size(); ++c) out.values[r * names.size() + c] = at(r, source[c]);
    return out;
}

std::optional<std::size_t> FeatureTable::find(const std::string& id) const {
    const auto it = std::find(ids.begin(), ids.end(), id);
    if (it == ids.end()) return std::nullopt;
    return static_cast<std::size_t>(it - ids.begin());
}

std::vector<std::string> split_csv_line(const std::string& line) {
    std::vector<std::string> fields;
    std::string current;
    auto flush = [&] {
        const auto first = current.find_first_not_of(" \t\r");
        const auto last = current.find_last_not_of(" \t\r");
        fields.push_back(first == std::string::npos ? std::string() : current.substr(first, last - first + 1));
        current.clear();
    };
    for (char ch : line) {
        if (ch == ',')
            flush();
        else
            current.push_back(ch);
    }
    flush();
    return fields;
}

namespace {

std::string format_double(double v) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), v);  // shortest round-trip form
    return std::string(buffer, result.ptr);
}

double parse_double(const std::string& text, const std::string& file, std::size_t line, const std::string& column) {
    double v = 0;
    const auto result = std::from_chars(text.data(), text.data() + text.size(), v);
    if (result.ec != std::errc() || result.ptr != text.data() + text.size() || !std::isfinite(v))
        throw Error::input(file, "line " + std::to_string(line) + ", column '" + column + "': '" + text + "' is not a finite number");
    return v;
}

// A feature value: a finite number, or `nan` / an empty field for a missing value (a feature that
// could not be computed for that tree). Infinities are errors.
double parse_feature(const std::string& text, const std::string& file, std::size_t line, const std::string& column) {
    if (text.empty() || text == "nan" || text == "NaN" || text == "NA") return std::numeric_limits<double>::quiet_NaN();
    return parse_double(text, file, line, column);
}

std::vector<std::string> read_lines(const std::filesystem::path& path) {
    std::istringstream in(read_file(path));
    std::vector<std::string> lines;
    std::string line;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        lines.push_back(line);
    }
    while (!lines.empty() && lines.back().find_first_not_of(" \t") == std::string::npos) lines.pop_back();
    return lines;
}

// Index of the first header column whose lower-case name is one of `aliases`.
std::optional<std::size_t> find_column(const std::vector<std::string>& header, std::initializer_list<const char*> aliases) {
    for (const char* alias : aliases)
        for (std::size_t c = 0; c < header.size(); ++c) {
            std::string name = header[c];
            std::transform(name.begin(), name.end(), name.begin(), [](unsigned char ch) { return std::tolower(ch); });
            if (name == alias) return c;
        }
    return std::nullopt;
}

}  // namespace

FeatureTable read_feature_csv(const std::filesystem::path& path) {
    const std::string file = path.string();
    const auto lines = read_lines(path);
    if (lines.empty()) throw Error::input(file, "empty feature table (expected a header 'id,<feature>,...')");
    const auto header = split_csv_line(lines.front());
    if (header.size() < 2 || header.front() != "id") throw Error::input(file, "line 1: expected a header 'id,<feature>,...'");
    FeatureTable table;
    table.feature_names.assign(header.begin() + 1, header.end());
    std::map<std::string, std::size_t> seen;
    for (std::size_t c = 0; c < table.feature_names.size(); ++c)
        if (!seen.emplace(table.feature_names[c], c).second)
            throw Error::input(file, "line 1: feature '" + table.feature_names[c] + "' appears twice");
    std::vector<double> row(table.cols());
    for (std::size_t l = 1; l < lines.size(); ++l) {
        const auto fields = split_csv_line(lines[l]);
        if (fields.size() != header.size())
            throw Error::input(file, "line " + std::to_string(l + 1) + ": " + std::to_string(fields.size()) + " fields, the header has " +
                                             std::to_string(header.size()));
        for (std::size_t c = 0; c < table.cols(); ++c) row[c] = parse_feature(fields[c + 1], file, l + 1, header[c + 1]);
        table.add_row(fields[0], row);
    }
    if (table.rows() == 0) throw Error::input(file, "no rows after the header");
    return table;
}

void write_feature_csv(const FeatureTable& table, const std::filesystem::path& path) {
    write_atomically(path, [&](std::ostream& out) {
        out << "id";
        for (const auto& name : table.feature_names) out << ',' << name;
        out << '\n';
        for (std::size_t r = 0; r < table.rows(); ++r) {
            out << table.ids[r];
            for (std::size_t c = 0; c < table.cols(); ++c) out << ',' << format_double(table.at(r, c));
            out << '\n';
        }
    });
}

std::vector<TreeLabel> read_labels_csv(const std::filesystem::path& path) {
    const std::string file = path.string();
    const auto lines = read_lines(path);
    if (lines.empty()) throw Error::input(file, "empty labels file (expected a header with 'id' and 'species')");
    const auto header = split_csv_line(lines.front());
    const auto id_col = find_column(header, {"id", "tree", "tree_id", "treeid", "file"});
    const auto species_col = find_column(header, {"species", "label", "class"});
    if (!id_col || !species_col)
        throw Error::input(file,
                           "line 1: the header needs an id column (id, tree, tree_id or file) and a species column "
                           "(species, label or class)");
    const auto x_col = find_column(header, {"x", "base_x"});
    const auto y_col = find_column(header, {"y", "base_y"});
    const auto group_col = find_column(header, {"tile", "site", "group", "plot"});
    const auto name_col = find_column(header, {"scientific_name", "genus"});
    std::vector<TreeLabel> labels;
    for (std::size_t l = 1; l < lines.size(); ++l) {
        const auto fields = split_csv_line(lines[l]);
        if (fields.size() != header.size())
            throw Error::input(file, "line " + std::to_string(l + 1) + ": " + std::to_string(fields.size()) + " fields, the header has " +
                                             std::to_string(header.size()));
        TreeLabel label;
        label.id = fields[*id_col];
        label.species = fields[*species_col];
        if (label.id.empty() || label.species.empty()) throw Error::input(file, "line " + std::to_string(l + 1) + ": empty id or species");
        if (x_col && y_col) {
            label.x = parse_double(fields[*x_col], file, l + 1, header[*x_col]);
            label.y = parse_double(fields[*y_col], file, l + 1, header[*y_col]);
        }
        if (group_col) label.group = fields[*group_col];
        if (name_col) label.scientific_name = fields[*name_col];
        labels.push_back(std::move(label));
    }
    if (labels.empty()) throw Error::input(file, "no labels after the header");
    return labels;
}

std::vector<TreePosition> read_positions_csv(const std::filesystem::path& path) {
    const std::string file = path.string();
    const auto lines = read_lines(path);
    if (lines.empty()) throw Error::input(file, "empty positions file (expected a header with id, x and y)");
    const auto header = split_csv_line(lines.front());
    const auto id_col = find_column(header, {"id", "tree", "tree_id", "treeid", "file"});
    const auto x_col = find_column(header, {"x", "base_x"});
    const auto y_col = find_column(header, {"y", "base_y"});
    if (!id_col || !x_col || !y_col) throw Error::input(file, "line 1: the header needs an id column and x, y columns");
    std::vector<TreePosition> out;
    for (std::size_t l = 1; l < lines.size(); ++l) {
        const auto fields = split_csv_line(lines[l]);
        if (fields.size() != header.size())
            throw Error::input(file, "line " + std::to_string(l + 1) + ": " + std::to_string(fields.size()) + " fields, the header has " +
                                             std::to_string(header.size()));
        out.push_back({fields[*id_col], parse_double(fields[*x_col], file, l + 1, header[*x_col]),
                       parse_double(fields[*y_col], file, l + 1, header[*y_col])});
    }
    return out;
}

std::vector<TreeLabel> labels_for_rows(const FeatureTable& table, const std::vector<TreeLabel>& labels, const std::string& labels_file) {
    std::unordered_map<std::string, const TreeLabel*> by_id;
    for (const auto& label : labels) by_id.emplace(label.id, &label);
    std::vector<TreeLabel> out;
    out.reserve(table.rows());
    for (const auto& id : table.ids) {
        const auto it = by_id.find(id);
        if (it == by_id.end()) throw Error::input(labels_file, "no label for tree '" + id + "'");
        out.push_back(*it->second);
    }
    return out;
}

}  // namespace treelobes::classify
