// PCD through PCL's reader and writer. Fields x y z are required; intensity, rgb/rgba and
// label map to the standard attributes; every other single-valued field becomes an extra.
#include "core/atomic_file.hpp"
#include "core/attribute_value.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/log.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

// Reads field `f` of point `i` as double whatever its stored type.
double field_value(const pcl::PCLPointCloud2& blob, const pcl::PCLPointField& f, std::size_t i) {
    const std::uint8_t* p = blob.data.data() + i * blob.point_step + f.offset;
    auto get = [p]<typename T>(T) {
        T v;
        std::memcpy(&v, p, sizeof v);
        return static_cast<double>(v);
    };
    switch (f.datatype) {
        case pcl::PCLPointField::INT8:
            return get(std::int8_t{});
        case pcl::PCLPointField::UINT8:
            return get(std::uint8_t{});
        case pcl::PCLPointField::INT16:
            return get(std::int16_t{});
        case pcl::PCLPointField::UINT16:
            return get(std::uint16_t{});
        case pcl::PCLPointField::INT32:
            return get(std::int32_t{});
        case pcl::PCLPointField::UINT32:
            return get(std::uint32_t{});
        case pcl::PCLPointField::FLOAT32:
            return get(float{});
        default:
            return get(double{});
    }
}

// Bytes of one value of a PCL datatype; 0 for a datatype PCL could not make of the header's
// SIZE and TYPE (e.g. a SIZE that is not a number).
std::size_t datatype_bytes(std::uint8_t datatype) {
    switch (datatype) {
        case pcl::PCLPointField::INT8:
        case pcl::PCLPointField::UINT8:
            return 1;
        case pcl::PCLPointField::INT16:
        case pcl::PCLPointField::UINT16:
            return 2;
        case pcl::PCLPointField::INT32:
        case pcl::PCLPointField::UINT32:
        case pcl::PCLPointField::FLOAT32:
            return 4;
        case pcl::PCLPointField::FLOAT64:
            return 8;
        default:
            return 0;
    }
}

// Every field must be of a known type and lie inside the point record, or reading it would run
// past the record (found by fuzz/pcd_fuzz.cpp: "SIZE 4 z 4" gave a field of no known type).
void check_fields(const pcl::PCLPointCloud2& blob, const std::string& name) {
    for (const auto& f : blob.fields) {
        const std::size_t bytes = datatype_bytes(f.datatype);
        if (bytes == 0) throw Error::input(name, "PCD field '" + f.name + "' has no valid SIZE and TYPE");
        if (static_cast<std::size_t>(f.offset) + bytes * std::max<std::size_t>(f.count, 1) > blob.point_step)
            throw Error::input(
                    name, "PCD field '" + f.name + "' does not fit in the point record of " + std::to_string(blob.point_step) + " bytes");
    }
}

AttributeType attribute_type(std::uint8_t datatype) {
    switch (datatype) {
        case pcl::PCLPointField::INT8:
            return AttributeType::Int8;
        case pcl::PCLPointField::UINT8:
            return AttributeType::UInt8;
        case pcl::PCLPointField::INT16:
            return AttributeType::Int16;
        case pcl::PCLPointField::UINT16:
            return AttributeType::UInt16;
        case pcl::PCLPointField::INT32:
            return AttributeType::Int32;
        case pcl::PCLPointField::UINT32:
            return AttributeType::UInt32;
        case pcl::PCLPointField::FLOAT32:
            return AttributeType::Float32;
        default:
            return AttributeType::Float64;
    }
}

const pcl::PCLPointField* find_field(const pcl::PCLPointCloud2& blob, const std::string& name) {
    for (const auto& f : blob.fields)
        if (f.name == name) return &f;
    return nullptr;
}

void store_field(const pcl::PCLPointCloud2& blob, const pcl::PCLPointField& f, const std::vector<std::size_t>& kept, PointCloud& cloud) {
    if (f.count != 1 || f.name == "x" || f.name == "y" || f.name == "z" || f.name == "_") return;
    if (f.name == "rgb" || f.name == "rgba") {
        for (std::size_t i : kept) {
            std::uint32_t packed;
            std::memcpy(&packed, blob.data.data() + i * blob.point_step + f.offset, 4);
            cloud.rgb.push_back({static_cast<std::uint16_t>((packed >> 16) & 0xff), static_cast<std::uint16_t>((packed >> 8) & 0xff),
                                 static_cast<std::uint16_t>(packed & 0xff)});
        }
        return;
    }
    std::vector<double> values;
    values.reserve(kept.size());
    for (std::size_t i : kept) values.push_back(field_value(blob, f, i));
    if (f.name == "intensity") {
        for (double v : values) cloud.intensity.push_back(attribute_value<std::uint16_t>(v));
    } else if (f.name == "classification") {
        for (double v : values) cloud.classification.push_back(attribute_value<std::uint8_t>(v));
    } else {
        cloud.extras.push_back({f.name, attribute_type(f.datatype), "", std::nullopt, std::move(values)});
    }
}

// Whether every value of a SIZE, COUNT, WIDTH, HEIGHT or POINTS line is a whole number, and every
// TYPE one of PCD's three letters. PCL threw std::length_error from inside its reader on a COUNT
// of "1%" (fuzzing, 60 s with seed 1).
bool pcd_values_valid(const std::string& keyword, const std::string& value) {
    if (keyword == "TYPE") return value == "I" || value == "U" || value == "F";
    if (keyword == "SIZE" || keyword == "COUNT" || keyword == "WIDTH" || keyword == "HEIGHT" || keyword == "POINTS")
        return value.size() <= 10 && value.find_first_not_of("0123456789") == std::string::npos;
    return true;
}

// PCL's reader dereferences null pointers on headers without their FIELDS, SIZE or TYPE lines
// (found by fuzz/pcd_fuzz.cpp), so the header is checked first: only PCD keywords, every required one,
// FIELDS, SIZE, TYPE (and COUNT) with the same number of entries, numbers where PCD has numbers.
void check_pcd_header(const fs::path& path, const std::string& name) {
    std::ifstream in(path, std::ios::binary);
    std::map<std::string, std::size_t> entries;  // keyword -> values on its line
    std::string line;
    for (int lines = 0; lines < 64 && std::getline(in, line); ++lines) {
        std::istringstream words(line);
        std::string keyword, value;
        if (!(words >> keyword) || keyword[0] == '#') continue;
        // PCL's parser freed memory it then used on a FIELDS line with NUL bytes (ASan, fuzzing):
        // a PCD header line (comments aside) is printable ASCII.
        if (!std::all_of(line.begin(), line.end(), [](char c) { return (c >= 0x20 && c < 0x7f) || c == '\t' || c == '\r'; }))
            throw Error::input(name, "PCD header line " + std::to_string(lines + 1) + " holds bytes that are not printable text");
        static const std::set<std::string> kKeywords{"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                                     "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
        if (!kKeywords.count(keyword))  // PCL crashed on a header line of binary garbage (fuzzing in CI)
            throw Error::input(name, "PCD header line " + std::to_string(lines + 1) + " is not a PCD header line");
        if (entries.count(keyword)) throw Error::input(name, "PCD header repeats its " + keyword + " line");
        std::size_t count = 0;
        while (words >> value) {
            if (!pcd_values_valid(keyword, value))
                throw Error::input(name, "PCD header: " + keyword + " value '" + value.substr(0, 16) + "' is not valid");
            ++count;
        }
        entries[keyword] = count;
        if (keyword == "DATA") break;
    }
    for (const char* keyword : {"FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT", "POINTS", "DATA"})
        if (!entries.count(keyword)) throw Error::input(name, std::string("PCD header has no ") + keyword + " line");
    const std::size_t fields = entries["FIELDS"];
    if (fields == 0 || entries["SIZE"] != fields || entries["TYPE"] != fields || (entries.count("COUNT") && entries["COUNT"] != fields))
        throw Error::input(name, "PCD header: FIELDS, SIZE, TYPE and COUNT list different numbers of entries");
}

}  // namespace

PointCloud read_pcd(const fs::path& path) {
    const std::string name = path.string();
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // errors become our one-line message
    // PCL's reader dereferences a null pointer on an empty file (found by fuzz/pcd_fuzz.cpp).
    std::error_code error;
    if (fs::file_size(path, error) == 0 && !error) throw Error::input(name, "file is empty, expected a PCD header");
    check_pcd_header(path, name);
    pcl::PCLPointCloud2 blob;
    pcl::PCDReader reader;
    int status = 0;
    try {
        status = reader.read(name, blob);
    } catch (const std::exception& e) {
        // PCL throws standard exceptions (std::length_error, ...) on damaged files the header check
        // lets through (fuzzing, 60 s with seed 1): the file's fault, not ours.
        throw Error::input(name, std::string("PCL cannot read it: ") + e.what());
    }
    if (status < 0) throw Error::input(name, "cannot read PCD (malformed or truncated file)");
    check_fields(blob, name);
    const auto* fx = find_field(blob, "x");
    const auto* fy = find_field(blob, "y");
    const auto* fz = find_field(blob, "z");
    if (!fx || !fy || !fz) throw Error::input(name, "PCD has no x, y, z fields");
    const std::size_t n = static_cast<std::size_t>(blob.width) * blob.height;
    if (blob.data.size() < n * blob.point_step) throw Error::input(name, "PCD data is shorter than its header declares");

    PointCloud cloud;
    cloud.source.format = "pcd";
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d p(field_value(blob, *fx, i), field_value(blob, *fy, i), field_value(blob, *fz, i));
        if (!p.allFinite()) continue;  // PCL marks invalid points of organised clouds with NaN
        if (kept.empty())
            for (int k = 0; k < 3; ++k) cloud.origin[k] = std::abs(p[k]) >= 1e4 ? std::round(p[k] / 1000.0) * 1000.0 : 0.0;
        kept.push_back(i);
        cloud.positions.push_back((p - cloud.origin).cast<float>());
    }
    if (cloud.empty()) throw Error::input(name, n ? "all points have NaN/inf coordinates" : "PCD has no points");
    for (const auto& f : blob.fields) store_field(blob, f, kept, cloud);
    cloud.source.dropped_non_finite = n - kept.size();
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
