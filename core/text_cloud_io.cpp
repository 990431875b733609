// Delimited text point clouds (.xyz .txt .csv .pts .asc): x y z first, optional further columns.
//
// Accepted: space/tab runs, comma or semicolon separators; CRLF line ends; trailing blanks; a
// missing final newline; '#' comment lines; one optional header line (CloudCompare writes
// "//X,Y,Z,..."; any first line whose first field is not a number counts as a header). Named
// columns intensity/classification/red/green/blue map to the standard attributes, any other
// column becomes a float64 extra attribute (without a header: "column_4", "column_5", ...).
#include "core/attribute_value.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/atomic_file.hpp"
#include "core/log.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string_view>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

using Fields = std::vector<std::string_view>;

std::string lower(std::string_view s) {
    std::string out(s);
    std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return out;
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    return s;
}

void split(std::string_view line, char separator, Fields& fields) {
    fields.clear();
    if (separator == ' ') {  // runs of spaces and tabs
        std::size_t i = 0;
        while (i < line.size()) {
            while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
            const std::size_t start = i;
            while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
            if (i > start) fields.push_back(line.substr(start, i - start));
        }
        return;
    }
    std::size_t start = 0;
    for (std::size_t i = 0; i <= line.size(); ++i) {
        if (i == line.size() || line[i] == separator) {
            fields.push_back(trim(line.substr(start, i - start)));
            start = i + 1;
        }
    }
}

std::optional<double> parse_number(std::string_view text) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    double value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size()) {
        // from_chars rejects "nan"/"inf" spellings it does not know, e.g. "NaN", "Inf".
        const std::string l = lower(text);
        if (l == "nan" || l == "-nan") return std::nan("");
        if (l == "inf" || l == "infinity") return HUGE_VAL;
        if (l == "-inf" || l == "-infinity") return -HUGE_VAL;
        return std::nullopt;
    }
    return value;
}

char detect_separator(std::string_view line) {
    if (line.find(',') != std::string_view::npos) return ',';
    if (line.find(';') != std::string_view::npos) return ';';
    return ' ';
}

// Splits the buffer into lines without copying; the last line may lack its newline.
class LineReader {
public:
    explicit LineReader(std::string_view text) : text_(text) {}
    bool next(std::string_view& line) {
        if (pos_ >= text_.size()) return false;
        const std::size_t end = text_.find('\n', pos_);
        const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
        line = text_.substr(pos_, stop - pos_);
        pos_ = stop + 1;
        ++number_;
        return true;
    }
    std::size_t number() const { return number_; }

private:
    std::string_view text_;
    std::size_t pos_ = 0;
    std::size_t number_ = 0;
};

enum class Column { X, Y, Z, Intensity, Classification, Red, Green, Blue, Extra };

struct Layout {
    std::vector<Column> columns;
    std::vector<std::string> names;  // for extras
};

Layout layout_from_header(const Fields& header) {
    Layout layout;
    for (std::size_t i = 0; i < header.size(); ++i) {
        std::string name = lower(header[i]);
        while (!name.empty() && (name.front() == '/' || name.front() == '#')) name.erase(name.begin());
        Column column = Column::Extra;
        if (i < 3)
            column = static_cast<Column>(i);  // x y z always first, whatever they are called
        else if (name == "intensity" || name == "scalar_intensity")
            column = Column::Intensity;
        else if (name == "classification" || name == "scalar_classification")
            column = Column::Classification;
        else if (name == "r" || name == "red")
            column = Column::Red;
        else if (name == "g" || name == "green")
            column = Column::Green;
        else if (name == "b" || name == "blue")
            column = Column::Blue;
        layout.columns.push_back(column);
        layout.names.push_back(std::string(header[i]));
    }
    return layout;
}

Layout layout_without_header(std::size_t count) {
    Layout layout;
    for (std::size_t i = 0; i < count; ++i) {
        layout.columns.push_back(i < 3 ? static_cast<Column>(i) : Column::Extra);
        layout.names.push_back("column_" + std::to_string(i + 1));
    }
    return layout;
}

bool is_header(std::string_view line, const Fields& fields) {
    return line.starts_with("//") || fields.empty() || !parse_number(fields[0]).has_value();
}

// Per-axis origin: 0 for small coordinates (local == original), otherwise the first point
// rounded to 1 km so float local coordinates keep sub-millimetre precision.
Eigen::Vector3d choose_origin(const Eigen::Vector3d& first) {
    Eigen::Vector3d origin;
    for (int k = 0; k < 3; ++k) origin[k] = std::abs(first[k]) < 1e4 ? 0.0 : std::round(first[k] / 1000.0) * 1000.0;
    return origin;
}

struct Columns {
    std::vector<double> intensity, classification, red, green, blue;
    std::vector<std::vector<double>> extras;
};

void store_attributes(const Layout& layout, Columns& c, PointCloud& cloud) {
    auto to_u16 = [](const std::vector<double>& v) {
        std::vector<std::uint16_t> out(v.size());
        for (std::size_t i = 0; i < v.size(); ++i) out[i] = attribute_value<std::uint16_t>(v[i]);
        return out;
    };
    if (!c.intensity.empty()) cloud.intensity = to_u16(c.intensity);
    if (!c.classification.empty()) {
        cloud.classification.resize(c.classification.size());
        for (std::size_t i = 0; i < c.classification.size(); ++i)
            cloud.classification[i] = attribute_value<std::uint8_t>(c.classification[i]);
    }
    if (!c.red.empty() && c.red.size() == c.green.size() && c.red.size() == c.blue.size()) {
        const auto r = to_u16(c.red), g = to_u16(c.green), b = to_u16(c.blue);
        cloud.rgb.resize(r.size());
        for (std::size_t i = 0; i < r.size(); ++i) cloud.rgb[i] = {r[i], g[i], b[i]};
    }
    std::size_t e = 0;
    for (std::size_t i = 0; i < layout.columns.size(); ++i) {
        if (layout.columns[i] != Column::Extra) continue;
        ExtraAttribute attribute;
        attribute.name = layout.names[i];
        attribute.type = AttributeType::Float64;
        attribute.values = std::move(c.extras[e++]);
        cloud.extras.push_back(std::move(attribute));
    }
}

}  // namespace

PointCloud read_text_cloud(const fs::path& path) {
    const std::string text = read_file(path);
    const std::string name = path.string();
    if (text.find('\0') != std::string::npos)
        throw Error::input(name, "contains binary data, expected a text point cloud (x y z per line)");

    PointCloud cloud;
    cloud.source.format = file_extension(path);
    LineReader lines(text);
    std::string_view line;
    Fields fields;
    std::optional<Layout> layout;
    char separator = ' ';
    Columns columns;
    bool origin_set = false;
    std::size_t dropped = 0;

    while (lines.next(line)) {
        line = trim(line);
        if (line.empty() || line.front() == '#') continue;
        if (!layout) {
            separator = detect_separator(line);
            split(line, separator, fields);
            if (is_header(line, fields)) {
                layout = layout_from_header(fields);
                if (layout->columns.size() < 3)
                    throw Error::input(name, "line " + std::to_string(lines.number()) + ": header has fewer than 3 columns");
                continue;
            }
            layout = layout_without_header(fields.size());
        }
        split(line, separator, fields);
        if (fields.size() < 3)
            throw Error::input(name, "line " + std::to_string(lines.number()) + ": expected at least 3 numbers (x y z), found " +
                                             std::to_string(fields.size()) + " field(s)");
        double values[3];
        for (int k = 0; k < 3; ++k) {
            const auto v = parse_number(fields[k]);
            if (!v)
                throw Error::input(name, "line " + std::to_string(lines.number()) + ": '" + std::string(fields[k]) + "' is not a number");
            values[k] = *v;
        }
        if (!std::isfinite(values[0]) || !std::isfinite(values[1]) || !std::isfinite(values[2])) {
            ++dropped;
            continue;
        }
        const Eigen::Vector3d p(values[0], values[1], values[2]);
        if (!origin_set) {
            cloud.origin = choose_origin(p);
            origin_set = true;
            if (columns.extras.empty())
                columns.extras.resize(static_cast<std::size_t>(std::count(layout->columns.begin(), layout->columns.end(), Column::Extra)));
        }
        cloud.positions.push_back((p - cloud.origin).cast<float>());
        std::size_t e = 0;
        for (std::size_t i = 3; i < layout->columns.size(); ++i) {
            double v = std::nan("");
            if (i < fields.size()) {
                const auto parsed = parse_number(fields[i]);
                if (!parsed)
                    throw Error::input(name, "line " + std::to_string(lines.number()) + ", column " + std::to_string(i + 1) + ": '" +
                                                     std::string(fields[i]) + "' is not a number");
                v = *parsed;
            }
            switch (layout->columns[i]) {
                case Column::Intensity:
                    columns.intensity.push_back(v);
                    break;
                case Column::Classification:
                    columns.classification.push_back(v);
                    break;
                case Column::Red:
                    columns.red.push_back(v);
                    break;
                case Column::Green:
                    columns.green.push_back(v);
                    break;
                case Column::Blue:
                    columns.blue.push_back(v);
                    break;
                default:
                    columns.extras[e++].push_back(v);
                    break;
            }
        }
    }
    if (cloud.empty()) {
        if (dropped > 0) throw Error::input(name, "all " + std::to_string(dropped) + " points have NaN/inf coordinates");
        throw Error::input(name, "no points found (empty file or header only)");
    }
    if (layout) store_attributes(*layout, columns, cloud);
    cloud.source.dropped_non_finite = dropped;
    if (dropped) log_warn(name + ": dropped " + std::to_string(dropped) + " point(s) with NaN/inf coordinates");
    cloud.check_consistent(name);
    return cloud;
}

void write_text_cloud(const PointCloud& cloud, const fs::path& path) {
    cloud.check_consistent(path.string());
    const char separator = file_extension(path) == "csv" ? ',' : ' ';
    // Columns after x y z, in the order the reader maps back onto attributes.
    std::vector<std::string> header{"x", "y", "z"};
    if (!cloud.intensity.empty()) header.emplace_back("intensity");
    if (!cloud.classification.empty()) header.emplace_back("classification");
    if (!cloud.rgb.empty()) header.insert(header.end(), {"red", "green", "blue"});
    for (const auto& attribute : cloud.extras) header.push_back(attribute.name);

    write_atomically(path, [&](std::ostream& out) {
        if (header.size() > 3) {  // plain x y z files stay headerless for old tools
            for (std::size_t i = 0; i < header.size(); ++i) out << (i ? std::string(1, separator) : "") << header[i];
            out << '\n';
        }
        char buffer[64];
        auto put_number = [&](double value) {
            const auto r = std::to_chars(buffer, buffer + sizeof buffer, value);
            out.put(separator);
            out.write(buffer, r.ptr - buffer);
        };
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            const Eigen::Vector3d p = cloud.global(i);
            for (int k = 0; k < 3; ++k) {
                // 0.1 mm is below every scanner's precision and keeps the files short.
                const int n = std::snprintf(buffer, sizeof buffer, "%.4f", p[k]);
                if (k) out.put(separator);
                out.write(buffer, n);
            }
            if (!cloud.intensity.empty()) put_number(cloud.intensity[i]);
            if (!cloud.classification.empty()) put_number(cloud.classification[i]);
            if (!cloud.rgb.empty())
                for (int c = 0; c < 3; ++c) put_number(cloud.rgb[i][c]);
            for (const auto& attribute : cloud.extras) put_number(attribute.values[i]);
            out.put('\n');
        }
    });
}

}  // namespace treelobes
