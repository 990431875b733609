#include "core/qsm_io.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

constexpr std::array<const char*, 14> kCsvColumns = {"ID",          "parentID", "startX",    "startY",         "startZ",
                                                     "endX",        "endY",     "endZ",      "radius",         "length",
                                                     "branchOrder", "branchID", "segmentID", "parentSegmentID"};

bool is_separator(char c) { return std::isspace(static_cast<unsigned char>(c)) || c == ',' || c == ';'; }

bool blank_or_comment(const std::string& line) {
    const auto first = line.find_first_not_of(" \t\r");
    return first == std::string::npos || line[first] == '#';
}

// Numbers of one line; false when a field is not a number.
bool parse_numbers(const std::string& line, std::vector<double>& out) {
    out.clear();
    const char* p = line.data();
    const char* end = p + line.size();
    while (p < end) {
        while (p < end && is_separator(*p)) ++p;
        if (p >= end) break;
        double v = 0;
        const auto [next, ec] = std::from_chars(p, end, v);
        if (ec != std::errc() || next == p || (next < end && !is_separator(*next))) return false;
        out.push_back(v);
        p = next;
    }
    return !out.empty();
}

std::vector<std::string> split_header(const std::string& line) {
    std::vector<std::string> names;
    std::string name;
    for (char c : line) {
        if (is_separator(c) || c == '"') {
            if (!name.empty()) names.push_back(name);
            name.clear();
        } else
            name += c;
    }
    if (!name.empty()) names.push_back(name);
    return names;
}

std::string line_error(std::size_t line, const std::string& what) { return "line " + std::to_string(line) + ": " + what; }

int as_index(double value, const std::string& name, std::size_t line, const char* column) {
    if (value != std::floor(value) || std::abs(value) > 1e9)
        throw Error::input(name, line_error(line, std::string(column) + " must be an integer"));
    return static_cast<int>(value);
}

QsmCylinder cylinder_from_treeqsm_row(const std::vector<double>& c, const std::string& name, std::size_t line) {
    QsmCylinder cyl;
    cyl.radius = c[0];
    cyl.length = c[1];
    cyl.start = {c[2], c[3], c[4]};
    const Eigen::Vector3d axis(c[5], c[6], c[7]);
    if (!(axis.norm() > 1e-9)) throw Error::input(name, line_error(line, "zero axis"));
    cyl.axis = axis.normalized();
    cyl.parent = c.size() > 8 ? as_index(c[8], name, line, "parent") - 1 : -1;
    cyl.extension = c.size() > 9 ? as_index(c[9], name, line, "extension") - 1 : -1;
    cyl.added = c.size() > 10 && c[10] != 0;
    cyl.unmodified_radius = c.size() > 11 ? c[11] : c[0];
    cyl.branch = c.size() > 12 ? as_index(c[12], name, line, "branch") - 1 : 0;
    cyl.branch_order = c.size() > 13 ? as_index(c[13], name, line, "branch order") : 0;
    cyl.position_in_branch = c.size() > 14 ? as_index(c[14], name, line, "position in branch") - 1 : 0;
    return cyl;
}

QsmModel read_treeqsm(std::istream& in, const std::string& name) {
    QsmModel model;
    model.format = "treeqsm";
    std::string line;
    std::vector<double> values;
    std::size_t line_number = 0, columns = 0;
    while (std::getline(in, line)) {
        ++line_number;
        if (blank_or_comment(line)) continue;
        if (!parse_numbers(line, values)) throw Error::input(name, line_error(line_number, "expected numbers"));
        if (columns == 0) {
            columns = values.size();
            if (columns < 8) throw Error::input(name, line_error(line_number, "a TreeQSM cylinder table needs at least 8 columns"));
        }
        if (values.size() != columns)
            throw Error::input(name, line_error(line_number, "expected " + std::to_string(columns) + " columns, found " +
                                                                     std::to_string(values.size())));
        model.cylinders.push_back(cylinder_from_treeqsm_row(values, name, line_number));
    }
    return model;
}

// Parents and extensions of CSV rows come as IDs; an extension is the child on the same branch.
QsmModel read_csv(std::istream& in, const std::string& name) {
    QsmModel model;
    model.format = "csv";
    std::string line;
    std::size_t line_number = 0;
    std::map<std::string, std::size_t> column;
    while (column.empty() && std::getline(in, line)) {
        ++line_number;
        if (blank_or_comment(line)) continue;
        const auto names = split_header(line);
        // A repeated name would leave the rows wider than the columns counted (an overflow found
        // by fuzzing, 60 s with seed 1).
        for (std::size_t i = 0; i < names.size(); ++i)
            if (!column.emplace(names[i], i).second)
                throw Error::input(name, line_error(line_number, "the header names column '" + names[i].substr(0, 32) + "' twice"));
    }
    for (const char* required : kCsvColumns)
        if (!column.contains(required)) throw Error::input(name, std::string("QSM CSV header lacks column ") + required);
    const auto at = [&](const std::vector<double>& row, const char* key) { return row[column.at(key)]; };
    std::vector<double> values;
    std::vector<long long> ids, parent_ids;
    std::map<long long, int> row_of_id;
    while (std::getline(in, line)) {
        ++line_number;
        if (blank_or_comment(line)) continue;
        if (!parse_numbers(line, values)) throw Error::input(name, line_error(line_number, "expected numbers"));
        if (values.size() < column.size())
            throw Error::input(name, line_error(line_number, "expected " + std::to_string(column.size()) + " columns, found " +
                                                                     std::to_string(values.size())));
        QsmCylinder cyl;
        cyl.start = {at(values, "startX"), at(values, "startY"), at(values, "startZ")};
        const Eigen::Vector3d end(at(values, "endX"), at(values, "endY"), at(values, "endZ"));
        if (!(end - cyl.start).allFinite() || !((end - cyl.start).norm() > 1e-12))
            throw Error::input(name, line_error(line_number, "start and end coincide"));
        cyl.axis = (end - cyl.start).normalized();
        cyl.length = at(values, "length");
        cyl.radius = cyl.unmodified_radius = at(values, "radius");
        cyl.branch_order = as_index(at(values, "branchOrder"), name, line_number, "branchOrder");
        cyl.branch = as_index(at(values, "branchID"), name, line_number, "branchID");
        const long long id = as_index(at(values, "ID"), name, line_number, "ID");
        if (!row_of_id.emplace(id, static_cast<int>(model.cylinders.size())).second)
            throw Error::input(name, line_error(line_number, "ID " + std::to_string(id) + " repeated"));
        ids.push_back(id);
        parent_ids.push_back(as_index(at(values, "parentID"), name, line_number, "parentID"));
        model.cylinders.push_back(cyl);
    }
    for (std::size_t i = 0; i < model.cylinders.size(); ++i) {
        const auto parent = row_of_id.find(parent_ids[i]);
        if (parent == row_of_id.end() || parent_ids[i] == ids[i]) continue;
        auto& c = model.cylinders[i];
        c.parent = parent->second;
        auto& p = model.cylinders[static_cast<std::size_t>(c.parent)];
        if (p.extension < 0 && p.branch == c.branch) p.extension = static_cast<int>(i);
    }
    return model;
}

// Cylinders in an order where every parent precedes its children (roots in index order, then
// depth first). Throws when parents form a cycle.
std::vector<int> parents_first_order(const QsmModel& model, const std::string& name) {
    const std::size_t n = model.cylinders.size();
    std::vector<std::vector<int>> children(n);
    std::vector<int> order;
    order.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
        if (model.cylinders[i].parent >= 0) children[static_cast<std::size_t>(model.cylinders[i].parent)].push_back(static_cast<int>(i));
    for (std::size_t i = 0; i < n; ++i) {
        if (model.cylinders[i].parent >= 0) continue;
        std::vector<int> stack{static_cast<int>(i)};
        while (!stack.empty()) {
            const int c = stack.back();
            stack.pop_back();
            order.push_back(c);
            for (auto it = children[static_cast<std::size_t>(c)].rbegin(); it != children[static_cast<std::size_t>(c)].rend(); ++it)
                stack.push_back(*it);
        }
    }
    if (order.size() != n) throw Error::input(name, "QSM parent links form a cycle");
    return order;
}

// The CSV has no position in branch: count along each branch from its first cylinder.
void derive_positions_in_branch(QsmModel& model, const std::string& name) {
    for (int i : parents_first_order(model, name)) {
        auto& c = model.cylinders[static_cast<std::size_t>(i)];
        const QsmCylinder* parent = c.parent >= 0 ? &model.cylinders[static_cast<std::size_t>(c.parent)] : nullptr;
        c.position_in_branch = parent && parent->branch == c.branch ? parent->position_in_branch + 1 : 0;
    }
}

void write_number(std::string& out, const char* format, double value) {
    char text[40];
    std::snprintf(text, sizeof text, format, value == 0 ? 0.0 : value);  // no "-0"
    out += text;
}

}  // namespace

double QsmCylinder::volume() const { return std::numbers::pi * radius * radius * length; }

double QsmModel::volume() const {
    double v = 0;
    for (const auto& c : cylinders) v += c.volume();
    return v;
}

double QsmModel::total_length() const {
    double l = 0;
    for (const auto& c : cylinders) l += c.length;
    return l;
}

void QsmModel::validate(const std::string& name) const {
    const int n = static_cast<int>(cylinders.size());
    for (int i = 0; i < n; ++i) {
        const auto& c = cylinders[static_cast<std::size_t>(i)];
        const std::string which = "cylinder " + std::to_string(i + 1);
        if (!std::isfinite(c.radius) || !std::isfinite(c.length) || !c.start.allFinite() || !c.axis.allFinite() ||
            !std::isfinite(c.unmodified_radius))
            throw Error::input(name, which + " has a non-finite value");
        if (c.radius < 0 || c.length < 0) throw Error::input(name, which + " has a negative radius or length");
        if (c.parent >= n || c.parent < -1 || c.parent == i) throw Error::input(name, which + " has an invalid parent");
        if (c.extension >= n || c.extension < -1 || c.extension == i) throw Error::input(name, which + " has an invalid extension");
        if (c.branch_order < 0) throw Error::input(name, which + " has a negative branch order");
    }
    parents_first_order(*this, name);
}

void QsmModel::derive_segments() {
    const std::vector<int> order = parents_first_order(*this, "QSM");
    std::vector<int> child_count(cylinders.size(), 0);
    for (const auto& c : cylinders)
        if (c.parent >= 0) ++child_count[static_cast<std::size_t>(c.parent)];
    int next = 0;
    for (int i : order) {
        auto& c = cylinders[static_cast<std::size_t>(i)];
        const bool continues = c.parent >= 0 && cylinders[static_cast<std::size_t>(c.parent)].extension == i &&
                               child_count[static_cast<std::size_t>(c.parent)] == 1;
        c.segment = continues ? cylinders[static_cast<std::size_t>(c.parent)].segment : next++;
    }
}

QsmFileKind detect_qsm_file(const fs::path& path, std::size_t* columns) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    std::vector<double> values;
    for (int lines = 0; lines < 20 && std::getline(in, line); ++lines) {
        if (blank_or_comment(line)) continue;
        if (parse_numbers(line, values)) {
            if (columns) *columns = values.size();
            return values.size() >= 8 ? QsmFileKind::TreeQsm : QsmFileKind::None;
        }
        const auto names = split_header(line);
        if (columns) *columns = names.size();
        const bool csv = std::all_of(kCsvColumns.begin(), kCsvColumns.end(),
                                     [&](const char* c) { return std::find(names.begin(), names.end(), c) != names.end(); });
        return csv ? QsmFileKind::Csv : QsmFileKind::None;
    }
    return QsmFileKind::None;
}

QsmModel read_qsm(const fs::path& path) {
    const std::string name = path.string();
    const QsmFileKind kind = detect_qsm_file(path);
    std::istringstream in(read_file(path));
    if (kind == QsmFileKind::None)
        throw Error::input(name, "not a QSM: expected a TreeQSM cylinder table or a SimpleForest/rTwig CSV header");
    QsmModel model = kind == QsmFileKind::Csv ? read_csv(in, name) : read_treeqsm(in, name);
    if (model.cylinders.empty()) throw Error::input(name, "QSM has no cylinders");
    model.validate(name);
    if (kind == QsmFileKind::Csv) derive_positions_in_branch(model, name);
    model.derive_segments();
    return model;
}

void write_treeqsm_cylinders(const QsmModel& model, const fs::path& path) {
    std::string out;
    out.reserve(model.cylinders.size() * 160);
    for (const auto& c : model.cylinders) {
        const double columns[] = {c.radius,
                                  c.length,
                                  c.start.x(),
                                  c.start.y(),
                                  c.start.z(),
                                  c.axis.x(),
                                  c.axis.y(),
                                  c.axis.z(),
                                  static_cast<double>(c.parent + 1),
                                  static_cast<double>(c.extension + 1),
                                  c.added ? 1.0 : 0.0,
                                  c.unmodified_radius,
                                  static_cast<double>(c.branch + 1),
                                  static_cast<double>(c.branch_order),
                                  static_cast<double>(c.position_in_branch + 1)};
        for (std::size_t k = 0; k < std::size(columns); ++k) {
            if (k) out += '\t';
            // Positions keep millimetres of georeferenced coordinates; the rest 9 significant digits.
            write_number(out, k >= 2 && k <= 4 ? "%.12g" : "%.9g", columns[k]);
        }
        out += '\n';
    }
    write_file_atomically(path, out);
}

void write_qsm_csv(const QsmModel& model, const fs::path& path) {
    std::string out;
    for (std::size_t k = 0; k < kCsvColumns.size(); ++k) out += std::string(k ? "," : "") + kCsvColumns[k];
    out += '\n';
    for (std::size_t i = 0; i < model.cylinders.size(); ++i) {
        const auto& c = model.cylinders[i];
        const Eigen::Vector3d end = c.end();
        const int parent_segment = c.parent >= 0 ? model.cylinders[static_cast<std::size_t>(c.parent)].segment : -1;
        out += std::to_string(i) + ',' + std::to_string(c.parent);
        for (double v : {c.start.x(), c.start.y(), c.start.z(), end.x(), end.y(), end.z()}) {
            out += ',';
            write_number(out, "%.12g", v);
        }
        for (double v : {c.radius, c.length}) {
            out += ',';
            write_number(out, "%.9g", v);
        }
        out += ',' + std::to_string(c.branch_order) + ',' + std::to_string(c.branch) + ',' + std::to_string(c.segment) + ',' +
               std::to_string(parent_segment) + '\n';
    }
    write_file_atomically(path, out);
}

}  // namespace treelobes
