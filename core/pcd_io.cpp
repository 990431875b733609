// PCD, the Point Cloud Library's format (v0.7; pointclouds.org, "The PCD (Point Cloud Data) file
// format"). Read here: the header, then the body as ascii lines, binary records or an LZF block
// (liblzf) of the points field by field. PCL's reader crashed or allocated without bound on damaged
// files that fuzzing made (docs/fuzzing.md), so it reads no input of ours. Written through PCL's
// writer (binary). Fields x y z are required; intensity, rgb/rgba and classification map to the
// standard attributes; every other single-valued field becomes an extra.
#include "core/atomic_file.hpp"
#include "core/attribute_value.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/little_endian.hpp"
#include "core/log.hpp"
#include "core/memory_limit.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

#include <lzf.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

// One field of the header: FIELDS, SIZE, TYPE and COUNT at the same position.
struct PcdField {
    std::string name;
    std::size_t size = 0;    // bytes of one value: 1, 2, 4 or 8
    char type = 'F';         // I signed integer, U unsigned integer, F floating point
    std::size_t count = 1;   // values per point
    std::size_t offset = 0;  // of its first value in a point record
};

struct PcdHeader {
    std::vector<PcdField> fields;
    std::size_t points = 0;
    std::string data;               // ascii, binary or binary_compressed
    std::size_t record_bytes = 0;   // one point: every field's size x count
    std::uint64_t body_offset = 0;  // first byte after the DATA line
};

// A point record's bytes stay below this: the widest PCL descriptor (VFH) takes 308 floats.
constexpr std::size_t kMaxRecordBytes = 1 << 16;
// LZF codes at most 264 bytes in one back reference of three bytes: no valid block unpacks to more.
constexpr std::uint64_t kMaxLzfExpansion = 88;

// Whether every value of a SIZE, COUNT, WIDTH, HEIGHT or POINTS line is a whole number, and every
// TYPE one of PCD's three letters. PCL threw std::length_error from inside its reader on a COUNT
// of "1%" (fuzzing, 60 s with seed 1).
bool pcd_values_valid(const std::string& keyword, const std::string& value) {
    if (keyword == "TYPE") return value == "I" || value == "U" || value == "F";
    if (keyword == "SIZE" || keyword == "COUNT" || keyword == "WIDTH" || keyword == "HEIGHT" || keyword == "POINTS")
        return value.size() <= 10 && value.find_first_not_of("0123456789") == std::string::npos;
    return true;
}

// The header's lines by keyword, each checked as text: only PCD keywords, each once, printable,
// numbers where PCD has numbers; ends at the DATA line, whose end `body_offset` receives.
std::map<std::string, std::vector<std::string>> header_lines(std::ifstream& in, const std::string& name, std::uint64_t& body_offset) {
    static const std::set<std::string> kKeywords{"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                                 "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
    std::map<std::string, std::vector<std::string>> lines;
    std::string line;
    for (int number = 1; number <= 64 && std::getline(in, line); ++number) {
        std::istringstream words(line);
        std::string keyword, value;
        if (!(words >> keyword) || keyword[0] == '#') continue;
        if (!std::all_of(line.begin(), line.end(), [](char c) { return (c >= 0x20 && c < 0x7f) || c == '\t' || c == '\r'; }))
            throw Error::input(name, "PCD header line " + std::to_string(number) + " holds bytes that are not printable text");
        if (!kKeywords.count(keyword)) throw Error::input(name, "PCD header line " + std::to_string(number) + " is not a PCD header line");
        if (lines.count(keyword)) throw Error::input(name, "PCD header repeats its " + keyword + " line");
        auto& values = lines[keyword];
        while (words >> value) {
            if (!pcd_values_valid(keyword, value))
                throw Error::input(name, "PCD header: " + keyword + " value '" + value.substr(0, 16) + "' is not valid");
            values.push_back(value);
        }
        if (keyword == "DATA") {
            body_offset = static_cast<std::uint64_t>(in.tellg());
            return lines;
        }
    }
    throw Error::input(name, "PCD header has no DATA line");
}

std::size_t header_number(const std::map<std::string, std::vector<std::string>>& lines, const char* keyword, const std::string& name) {
    const auto it = lines.find(keyword);
    if (it == lines.end() || it->second.size() != 1) throw Error::input(name, std::string("PCD header needs one ") + keyword + " value");
    return std::stoul(it->second[0]);  // at most 10 digits (pcd_values_valid)
}

// Checks one field's SIZE, TYPE and COUNT and places it in the point record.
void add_field(PcdHeader& header, PcdField field, const std::string& name) {
    const bool valid_size = field.type == 'F' ? field.size == 4 || field.size == 8
                                              : field.size == 1 || field.size == 2 || field.size == 4 || field.size == 8;
    if (!valid_size)
        throw Error::input(name,
                           "PCD field '" + field.name + "': SIZE " + std::to_string(field.size) + " is not a size of TYPE " + field.type);
    if (field.count == 0 || field.count > kMaxRecordBytes) throw Error::input(name, "PCD field '" + field.name + "': COUNT out of range");
    field.offset = header.record_bytes;
    header.record_bytes += field.size * field.count;
    if (header.record_bytes > kMaxRecordBytes) throw Error::input(name, "PCD point record is larger than 64 KiB");
    header.fields.push_back(std::move(field));
}

// The header of a PCD file (PCD v0.7; pointclouds.org, "The PCD (Point Cloud Data) file format").
PcdHeader read_pcd_header(std::ifstream& in, const std::string& name) {
    PcdHeader header;
    auto lines = header_lines(in, name, header.body_offset);
    for (const char* keyword : {"FIELDS", "SIZE", "TYPE"})
        if (!lines.count(keyword)) throw Error::input(name, std::string("PCD header has no ") + keyword + " line");
    const auto& names = lines["FIELDS"];
    if (!lines.count("COUNT")) lines["COUNT"] = std::vector<std::string>(names.size(), "1");
    if (names.empty() || lines["SIZE"].size() != names.size() || lines["TYPE"].size() != names.size() ||
        lines["COUNT"].size() != names.size())
        throw Error::input(name, "PCD header: FIELDS, SIZE, TYPE and COUNT list different numbers of entries");
    for (std::size_t i = 0; i < names.size(); ++i)
        add_field(header, {names[i], std::stoul(lines["SIZE"][i]), lines["TYPE"][i][0], std::stoul(lines["COUNT"][i])}, name);
    const std::size_t width = header_number(lines, "WIDTH", name), height = header_number(lines, "HEIGHT", name);
    header.points = header_number(lines, "POINTS", name);
    if (height == 0 ? header.points != 0 : header.points % height != 0 || header.points / height != width)
        throw Error::input(name, "PCD header: POINTS " + std::to_string(header.points) + " is not WIDTH x HEIGHT");
    const auto& data = lines["DATA"];
    header.data = data.size() == 1 ? data[0] : "";
    std::transform(header.data.begin(), header.data.end(), header.data.begin(), [](unsigned char c) { return std::tolower(c); });
    if (header.data != "ascii" && header.data != "binary" && header.data != "binary_compressed")
        throw Error::input(name, "PCD header: DATA must be ascii, binary or binary_compressed");
    return header;
}

std::vector<std::uint8_t> read_bytes(std::ifstream& in, std::uint64_t count, const std::string& name, const char* what) {
    std::vector<std::uint8_t> bytes(count);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(count)))
        throw Error::input(name, std::string("PCD ") + what + " is shorter than its header declares");
    return bytes;
}

// DATA binary_compressed: two little-endian uint32 (compressed and uncompressed size), then LZF
// data (liblzf) of the points field by field: every point's first field, then every point's second.
std::vector<std::uint8_t> read_compressed_records(std::ifstream& in, const PcdHeader& header, std::uint64_t available,
                                                  const std::string& name) {
    const std::vector<std::uint8_t> sizes = read_bytes(in, 8, name, "binary_compressed block");
    const std::uint32_t compressed = load<std::uint32_t>(sizes.data()), uncompressed = load<std::uint32_t>(sizes.data() + 4);
    const std::uint64_t expected = static_cast<std::uint64_t>(header.points) * header.record_bytes;
    if (uncompressed != expected)
        throw Error::input(name, "PCD binary_compressed block unpacks to " + std::to_string(uncompressed) + " bytes, the header declares " +
                                         std::to_string(expected));
    if (compressed > available - 8) throw Error::input(name, "PCD binary_compressed block is shorter than its size field declares");
    if (expected > compressed * kMaxLzfExpansion) throw Error::input(name, "PCD binary_compressed block is too small for its points");
    const std::vector<std::uint8_t> packed = read_bytes(in, compressed, name, "binary_compressed block");
    std::vector<std::uint8_t> columns(expected);
    if (expected > 0 && lzf_decompress(packed.data(), compressed, columns.data(), static_cast<unsigned>(expected)) != expected)
        throw Error::input(name, "PCD binary_compressed block is not valid LZF data");
    std::vector<std::uint8_t> records(expected);
    std::size_t column = 0;
    for (const auto& f : header.fields) {
        const std::size_t bytes = f.size * f.count;
        for (std::size_t i = 0; i < header.points; ++i, column += bytes)
            std::memcpy(records.data() + i * header.record_bytes + f.offset, columns.data() + column, bytes);
    }
    return records;
}

template <typename T>
bool parse_value(std::string_view text, std::uint8_t* out) {
    T value{};
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size()) return false;
    std::memcpy(out, &value, sizeof value);
    return true;
}

// One ascii value into its binary form in the point record.
bool parse_ascii_value(std::string_view text, const PcdField& f, std::uint8_t* out) {
    switch (f.type) {
        case 'F':
            return f.size == 4 ? parse_value<float>(text, out) : parse_value<double>(text, out);
        case 'I':
            return f.size == 1   ? parse_value<std::int8_t>(text, out)
                   : f.size == 2 ? parse_value<std::int16_t>(text, out)
                   : f.size == 4 ? parse_value<std::int32_t>(text, out)
                                 : parse_value<std::int64_t>(text, out);
        default:
            return f.size == 1   ? parse_value<std::uint8_t>(text, out)
                   : f.size == 2 ? parse_value<std::uint16_t>(text, out)
                   : f.size == 4 ? parse_value<std::uint32_t>(text, out)
                                 : parse_value<std::uint64_t>(text, out);
    }
}

// DATA ascii: one point per line, its values separated by spaces in field order.
std::vector<std::uint8_t> read_ascii_records(std::ifstream& in, const PcdHeader& header, const std::string& name) {
    std::vector<std::uint8_t> records;
    std::string line;
    std::size_t point = 0;
    while (std::getline(in, line)) {
        std::istringstream words(line);
        std::string word;
        if (!(words >> word)) continue;  // blank line
        if (point == header.points) throw Error::input(name, "PCD has more ascii points than its POINTS " + std::to_string(header.points));
        records.resize(records.size() + header.record_bytes);
        std::uint8_t* record = records.data() + point * header.record_bytes;
        for (const auto& f : header.fields)
            for (std::size_t k = 0; k < f.count; ++k, words >> word) {
                if (word.empty() || !parse_ascii_value(word, f, record + f.offset + k * f.size))
                    throw Error::input(name, "PCD ascii point " + std::to_string(point + 1) + ": '" + word.substr(0, 24) +
                                                     "' is not a value of field '" + f.name + "'");
                word.clear();
            }
        if (!word.empty()) throw Error::input(name, "PCD ascii point " + std::to_string(point + 1) + " has more values than its fields");
        ++point;
    }
    if (point != header.points)
        throw Error::input(name,
                           "PCD has " + std::to_string(point) + " ascii points, its header declares " + std::to_string(header.points));
    return records;
}

// Reads value `k` of field `f` of the record at `record` as double, whatever its stored type.
double field_value(const std::uint8_t* record, const PcdField& f, std::size_t k = 0) {
    const std::uint8_t* p = record + f.offset + k * f.size;
    auto get = [p]<typename T>(T) {
        T v;
        std::memcpy(&v, p, sizeof v);
        return static_cast<double>(v);
    };
    switch (f.type) {
        case 'F':
            return f.size == 4 ? get(float{}) : get(double{});
        case 'I':
            return f.size == 1   ? get(std::int8_t{})
                   : f.size == 2 ? get(std::int16_t{})
                   : f.size == 4 ? get(std::int32_t{})
                                 : get(std::int64_t{});
        default:
            return f.size == 1   ? get(std::uint8_t{})
                   : f.size == 2 ? get(std::uint16_t{})
                   : f.size == 4 ? get(std::uint32_t{})
                                 : get(std::uint64_t{});
    }
}

AttributeType attribute_type(const PcdField& f) {
    if (f.type == 'F') return f.size == 4 ? AttributeType::Float32 : AttributeType::Float64;
    static constexpr AttributeType kSigned[] = {AttributeType::Int8, AttributeType::Int16, AttributeType::Int32, AttributeType::Int64};
    static constexpr AttributeType kUnsigned[] = {AttributeType::UInt8, AttributeType::UInt16, AttributeType::UInt32,
                                                  AttributeType::UInt64};
    const int index = std::countr_zero(f.size);  // 1, 2, 4, 8 bytes -> 0..3
    return f.type == 'I' ? kSigned[index] : kUnsigned[index];
}

const PcdField* find_field(const PcdHeader& header, const std::string& name) {
    for (const auto& f : header.fields)
        if (f.name == name) return &f;
    return nullptr;
}

// Field `f` of the kept points into the cloud: rgb/rgba (PCL packs 8-bit red, green, blue into the
// 32 bits of one value), intensity and classification as the standard attributes, any other
// single-valued field as an extra; x, y, z, padding ("_") and multi-valued descriptors are left.
void store_field(const std::vector<std::uint8_t>& records, std::size_t record_bytes, const PcdField& f,
                 const std::vector<std::size_t>& kept, PointCloud& cloud) {
    if (f.count != 1 || f.name == "x" || f.name == "y" || f.name == "z" || f.name == "_") return;
    if ((f.name == "rgb" || f.name == "rgba") && f.size == 4) {
        for (std::size_t i : kept) {
            std::uint32_t packed;
            std::memcpy(&packed, records.data() + i * record_bytes + f.offset, 4);
            cloud.rgb.push_back({static_cast<std::uint16_t>((packed >> 16) & 0xff), static_cast<std::uint16_t>((packed >> 8) & 0xff),
                                 static_cast<std::uint16_t>(packed & 0xff)});
        }
        return;
    }
    std::vector<double> values;
    values.reserve(kept.size());
    for (std::size_t i : kept) values.push_back(field_value(records.data() + i * record_bytes, f));
    if (f.name == "intensity") {
        for (double v : values) cloud.intensity.push_back(attribute_value<std::uint16_t>(v));
    } else if (f.name == "classification") {
        for (double v : values) cloud.classification.push_back(attribute_value<std::uint8_t>(v));
    } else {
        cloud.extras.push_back({f.name, attribute_type(f), "", std::nullopt, std::move(values)});
    }
}

// The point records of the body, row by row, whatever the DATA encoding.
std::vector<std::uint8_t> read_records(std::ifstream& in, const PcdHeader& header, std::uint64_t file_size, const std::string& name) {
    const std::uint64_t bytes = static_cast<std::uint64_t>(header.points) * header.record_bytes;
    check_memory_estimate(bytes, name, std::to_string(header.points) + " PCD points");
    const std::uint64_t available = file_size - std::min(file_size, header.body_offset);
    if (header.data == "binary") {
        if (bytes > available) throw Error::input(name, "PCD data is shorter than its header declares");
        return read_bytes(in, bytes, name, "data");
    }
    if (header.data == "binary_compressed") {
        if (available < 8) throw Error::input(name, "PCD binary_compressed data has no size fields");
        return read_compressed_records(in, header, available, name);
    }
    return read_ascii_records(in, header, name);
}

}  // namespace

PointCloud read_pcd(const fs::path& path) {
    const std::string name = path.string();
    std::error_code error;
    const std::uint64_t file_size = fs::file_size(path, error);
    if (error) throw Error::input(name, "cannot read (" + error.message() + ")");
    if (file_size == 0) throw Error::input(name, "file is empty, expected a PCD header");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error::input(name, "cannot open");
    const PcdHeader header = read_pcd_header(in, name);
    const auto* fx = find_field(header, "x");
    const auto* fy = find_field(header, "y");
    const auto* fz = find_field(header, "z");
    if (!fx || !fy || !fz) throw Error::input(name, "PCD has no x, y, z fields");
    const std::vector<std::uint8_t> records = read_records(in, header, file_size, name);

    PointCloud cloud;
    cloud.source.format = "pcd";
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < header.points; ++i) {
        const std::uint8_t* record = records.data() + i * header.record_bytes;
        const Eigen::Vector3d p(field_value(record, *fx), field_value(record, *fy), field_value(record, *fz));
        if (!p.allFinite()) continue;  // organised clouds mark their invalid points with NaN
        if (kept.empty())
            for (int k = 0; k < 3; ++k) cloud.origin[k] = std::abs(p[k]) >= 1e4 ? std::round(p[k] / 1000.0) * 1000.0 : 0.0;
        kept.push_back(i);
        cloud.positions.push_back((p - cloud.origin).cast<float>());
    }
    if (cloud.empty()) throw Error::input(name, header.points ? "all points have NaN/inf coordinates" : "PCD has no points");
    for (const auto& f : header.fields) store_field(records, header.record_bytes, f, kept, cloud);
    cloud.source.dropped_non_finite = header.points - kept.size();
    if (cloud.source.dropped_non_finite)
        log_warn(name + ": dropped " + std::to_string(cloud.source.dropped_non_finite) + " point(s) with NaN/inf coordinates");
    return cloud;
}

void write_pcd(const PointCloud& cloud, const fs::path& path) {
    cloud.check_consistent(path.string());
    // Local float coordinates (PCD is a float format); the origin goes into the sidecar.
    pcl::PCLPointCloud2 blob;
    blob.width = static_cast<std::uint32_t>(cloud.size());
    blob.height = 1;
    blob.is_dense = true;
    std::uint32_t offset = 0;
    auto add_field = [&](const std::string& name) {
        pcl::PCLPointField f;
        f.name = name;
        f.offset = offset;
        f.datatype = pcl::PCLPointField::FLOAT32;
        f.count = 1;
        offset += 4;
        blob.fields.push_back(f);
    };
    for (const char* axis : {"x", "y", "z"}) add_field(axis);
    if (!cloud.intensity.empty()) add_field("intensity");
    for (const auto& attribute : cloud.extras) add_field(attribute.name);
    blob.point_step = offset;
    blob.row_step = offset * blob.width;
    blob.data.resize(static_cast<std::size_t>(blob.row_step));
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        std::vector<float> row{cloud.positions[i].x(), cloud.positions[i].y(), cloud.positions[i].z()};
        if (!cloud.intensity.empty()) row.push_back(cloud.intensity[i]);
        for (const auto& attribute : cloud.extras) row.push_back(static_cast<float>(attribute.values[i]));
        std::memcpy(blob.data.data() + i * blob.point_step, row.data(), blob.point_step);
    }
    write_atomically_via_path(path, [&](const fs::path& temporary) {
        pcl::PCDWriter writer;
        if (writer.writeBinary(temporary.string(), blob) < 0) throw Error::input(path.string(), "cannot write PCD");
    });
    write_georef_sidecar(path, cloud.origin, cloud.georef);
}

}  // namespace treelobes
