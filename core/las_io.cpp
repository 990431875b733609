// LAS 1.0-1.4 point clouds (ASPRS LAS specification 1.4 R15), uncompressed point formats 0-10.
//
// Reading keeps what the pipeline uses and what a writer needs to give the file back:
// coordinates (integer records -> scale/offset -> double origin + float local frame), intensity,
// return numbers, classification, RGB, GPS time, documented Extra Bytes and the CRS records
// (every LASF_Projection VLR/EVLR, verbatim). Point source id, scan angle, user data, flag bits,
// NIR and waveform packets are not kept.
//
// Every count and offset in the header is checked against the file size before anything is
// allocated or read, so a corrupt or truncated file gives one Error(InvalidInput) line, never a
// crash, a hang or a huge allocation. Points are streamed in chunks of a few megabytes.
//
// Writing: see choose_point_format / choose_minor_version / choose_frame below, and the summary
// at write_las.
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/input_file.hpp"
#include "core/las_io.hpp"
#include "core/laz_chunk.hpp"
#include "core/laz_layout.hpp"
#include "core/little_endian.hpp"
#include "core/memory_limit.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/version.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>

#include <tbb/blocked_range.h>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

using Bytes = std::vector<std::uint8_t>;

// Fixed-size character fields are NUL-padded (and not always NUL-terminated when full).
std::string load_string(const std::uint8_t* p, std::size_t size) {
    std::size_t length = 0;
    while (length < size && p[length] != 0) ++length;
    return {reinterpret_cast<const char*>(p), length};
}

void store_string(std::uint8_t* p, std::size_t size, std::string_view text) { std::memcpy(p, text.data(), std::min(size, text.size())); }

// Rounds and clamps a double into an integer type; NaN becomes 0. Out-of-range casts are
// undefined behaviour, so the comparison happens in double before the cast.
template <typename T>
T saturate(double value) {
    if (std::isnan(value)) return 0;
    value = std::round(value);
    if (value <= static_cast<double>(std::numeric_limits<T>::lowest())) return std::numeric_limits<T>::lowest();
    if (value >= static_cast<double>(std::numeric_limits<T>::max())) return std::numeric_limits<T>::max();
    return static_cast<T>(value);
}

// ---------------------------------------------------------------------------------------------
// Layout constants of the specification.

constexpr std::size_t kHeaderSize12 = 227;  // LAS 1.0-1.2
constexpr std::size_t kHeaderSize13 = 235;  // + start of waveform data packet record
constexpr std::size_t kHeaderSize14 = 375;  // + EVLRs and 64-bit point counts
constexpr std::size_t kVlrHeaderSize = 54;
constexpr std::size_t kEvlrHeaderSize = 60;
constexpr std::size_t kExtraBytesDescriptorSize = 192;
constexpr std::size_t kChunkBytes = std::size_t{4} << 20;  // points are streamed in ~4 MB chunks
// Largest coordinate magnitude accepted: origin and local positions then stay far inside float's
// range (3.4e38), so no decoded position can become infinite.
constexpr double kMaxCoordinate = 1e30;

// Byte offsets of public header fields.
namespace field {
constexpr std::size_t global_encoding = 6, version_major = 24, version_minor = 25, system_id = 26, software = 58, creation_day = 90,
                      creation_year = 92, header_size = 94, offset_to_points = 96, vlr_count = 100, point_format = 104, record_length = 105,
                      legacy_point_count = 107, legacy_by_return = 111, scale = 131, offset = 155,
                      bounds = 179,  // max x, min x, max y, min y, max z, min z
        waveform_start = 227, evlr_start = 235, evlr_count = 243, point_count = 247, by_return = 255;
}  // namespace field

constexpr std::uint16_t kGpsAdjustedStandardTime = 1;  // global encoding bit 0
constexpr std::uint16_t kWktCrs = 16;                  // global encoding bit 4 (LAS 1.4)

constexpr std::string_view kProjectionUser = "LASF_Projection";
constexpr std::string_view kSpecUser = "LASF_Spec";
constexpr std::uint16_t kExtraBytesRecord = 4;
constexpr std::uint16_t kWktRecord = 2112;
constexpr std::uint16_t kGeoKeyDirectoryRecord = 34735;
constexpr std::string_view kLaszipUser = "laszip encoded";  // LAZ specification 1.4, "LASzip VLR"
constexpr std::uint16_t kLaszipRecord = 22204;
constexpr std::string_view kCopcUser = "copc";  // COPC 1.0: info VLR 1, hierarchy EVLR 1000
constexpr std::uint16_t kCopcInfoRecord = 1;
constexpr std::uint16_t kCopcHierarchyRecord = 1000;

// Where the optional fields sit in a point record; -1 when the format lacks them.
struct PointFormat {
    int id;
    std::size_t size;  // standard record size; longer records carry extra bytes after it
    bool extended;     // formats 6-10: 4-bit return numbers, full-byte classification
    int gps_offset;
    int rgb_offset;
};

constexpr std::array<PointFormat, 11> kFormats = {{
        {0, 20, false, -1, -1},
        {1, 28, false, 20, -1},
        {2, 26, false, -1, 20},
        {3, 34, false, 20, 28},
        {4, 57, false, 20, -1},  // 1 + wave packet
        {5, 63, false, 20, 28},  // 3 + wave packet
        {6, 30, true, 22, -1},
        {7, 36, true, 22, 30},
        {8, 38, true, 22, 30},   // 7 + NIR
        {9, 59, true, 22, -1},   // 6 + wave packet
        {10, 67, true, 22, 30},  // 8 + wave packet
}};

// The first LAS minor version that defines a point format.
int minimum_minor_version(int format) {
    if (format <= 1) return 0;
    if (format <= 3) return 2;
    if (format <= 5) return 3;
    return 4;
}

std::size_t header_size_for(int minor) {
    if (minor <= 2) return kHeaderSize12;
    return minor == 3 ? kHeaderSize13 : kHeaderSize14;
}

// Extra Bytes data types 1..10 are uchar, char, ushort, short, ulong, long, ulonglong, longlong,
// float, double: the same order as AttributeType, so the code is the enum value + 1.
static_assert(static_cast<int>(AttributeType::UInt8) == 0 && static_cast<int>(AttributeType::Float64) == 9);

int las_data_type(AttributeType type) { return static_cast<int>(type) + 1; }
AttributeType attribute_type_of(int data_type) { return static_cast<AttributeType>(data_type - 1); }

std::size_t base_type_size(int data_type) {
    static constexpr std::array<std::size_t, 11> sizes = {0, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8};
    return data_type >= 1 && data_type <= 10 ? sizes[static_cast<std::size_t>(data_type)] : 0;
}

bool is_unsigned_type(AttributeType t) {
    return t == AttributeType::UInt8 || t == AttributeType::UInt16 || t == AttributeType::UInt32 || t == AttributeType::UInt64;
}
bool is_float_type(AttributeType t) { return t == AttributeType::Float32 || t == AttributeType::Float64; }

// A scale factor or offset for a message: "0.001", "1e+300" (std::to_string would print 300
// digits, or 0.000000 for a tiny scale).
std::string number_text(double value) {
    std::ostringstream text;
    text << value;
    return text.str();
}

std::string printable(const std::uint8_t* p, std::size_t size) {
    std::string out;
    static constexpr char hex[] = "0123456789abcdef";
    for (std::size_t i = 0; i < size; ++i) {
        if (p[i] >= 0x20 && p[i] < 0x7f) {
            out += static_cast<char>(p[i]);
        } else {
            out += "\\x";
            out += hex[p[i] >> 4];
            out += hex[p[i] & 15];
        }
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// Reading

struct LasHeader {
    int minor = 0;
    std::uint16_t global_encoding = 0;
    std::uint16_t header_size = 0;
    std::uint32_t offset_to_points = 0;
    std::uint32_t vlr_count = 0;
    int point_format = 0;
    std::uint16_t record_length = 0;
    std::uint64_t point_count = 0;
    Eigen::Vector3d scale, offset, min, max;
    std::uint64_t evlr_start = 0;
    std::uint32_t evlr_count = 0;
    bool compressed = false;  // LAZ: the point format byte has bit 7 (or 6) set
    Bytes raw;                // the header bytes as stored (header_size of them)
};

// Reads up to the largest header (375 bytes) and checks the signature and minimum length.
Bytes read_header_bytes(InputFile& file) {
    if (file.size() == 0) file.fail("file is empty, expected a LAS file starting with 'LASF'");
    const std::size_t available = static_cast<std::size_t>(std::min<std::uint64_t>(file.size(), kHeaderSize14));
    Bytes bytes = file.read(0, available, "header");
    if (available < 4 || std::memcmp(bytes.data(), "LASF", 4) != 0)
        file.fail("not a LAS file: signature is '" + printable(bytes.data(), std::min<std::size_t>(available, 4)) + "', expected 'LASF'");
    if (available < kHeaderSize12)
        file.fail("file is " + std::to_string(available) + " bytes, shorter than the 227-byte LAS header (truncated?)");
    bytes.resize(kHeaderSize14, 0);  // fields beyond the declared header size are never read
    return bytes;
}

void check_version(const InputFile& file, const Bytes& h) {
    const int major = h[field::version_major], minor = h[field::version_minor];
    if (major != 1 || minor > 4)
        file.fail("unsupported LAS version " + std::to_string(major) + "." + std::to_string(minor) + ", expected 1.0-1.4");
}

void check_layout(const InputFile& file, const LasHeader& h) {
    const std::size_t required = header_size_for(h.minor);
    if (h.header_size < required)
        file.fail("header size " + std::to_string(h.header_size) + " is smaller than the " + std::to_string(required) + " bytes LAS 1." +
                  std::to_string(h.minor) + " requires");
    if (h.header_size > file.size())
        file.fail("header size " + std::to_string(h.header_size) + " exceeds the file size (" + std::to_string(file.size()) + " bytes)");
    if (h.offset_to_points < h.header_size)
        file.fail("offset to point data " + std::to_string(h.offset_to_points) + " lies inside the " + std::to_string(h.header_size) +
                  "-byte header");
    if (h.offset_to_points > file.size())
        file.fail("offset to point data " + std::to_string(h.offset_to_points) + " lies beyond the end of the file (" +
                  std::to_string(file.size()) + " bytes; truncated?)");
}

void check_point_format(const InputFile& file, int format_byte, std::uint16_t record_length) {
    if (format_byte > 10) file.fail("unsupported point data format " + std::to_string(format_byte) + ", expected 0-10");
    const PointFormat& format = kFormats[static_cast<std::size_t>(format_byte)];
    if (record_length < format.size)
        file.fail("point record length " + std::to_string(record_length) + " is shorter than the " + std::to_string(format.size) +
                  " bytes point format " + std::to_string(format_byte) + " requires");
}

void check_scale_offset(const InputFile& file, const LasHeader& h) {
    static constexpr const char* axes[] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(h.scale[k]) || h.scale[k] == 0)
            file.fail(std::string(axes[k]) + " scale factor is " + number_text(h.scale[k]) +
                      ", expected a non-zero finite number such as 0.01 or 0.001");
        if (!std::isfinite(h.offset[k])) file.fail(std::string(axes[k]) + " offset is not a finite number");
        // Any 32-bit record must give a coordinate that float local positions can hold.
        if (std::abs(h.scale[k]) * 2147483648.0 + std::abs(h.offset[k]) > kMaxCoordinate)
            file.fail(std::string(axes[k]) + " scale " + number_text(h.scale[k]) + " and offset " + number_text(h.offset[k]) +
                      " give coordinates beyond 1e30, expected metre-range values");
    }
}

// Point records must fit between the start of point data and the end of the file. Dividing
// instead of multiplying avoids overflow with absurd counts.
void check_point_count(const InputFile& file, const LasHeader& h) {
    const std::uint64_t available = file.size() - h.offset_to_points;
    if (h.point_count > available / h.record_length)
        file.fail("header declares " + std::to_string(h.point_count) + " points of " + std::to_string(h.record_length) +
                  " bytes from byte " + std::to_string(h.offset_to_points) + ", but only " + std::to_string(available) +
                  " bytes follow (truncated file?)");
}

LasHeader read_header(InputFile& file) {
    const Bytes bytes = read_header_bytes(file);
    const std::uint8_t* p = bytes.data();
    check_version(file, bytes);
    LasHeader h;
    h.minor = p[field::version_minor];
    h.global_encoding = load<std::uint16_t>(p + field::global_encoding);
    h.header_size = load<std::uint16_t>(p + field::header_size);
    h.offset_to_points = load<std::uint32_t>(p + field::offset_to_points);
    h.vlr_count = load<std::uint32_t>(p + field::vlr_count);
    // LASzip marks compressed point data by setting bit 7 of the point format (some writers
    // also bit 6); the remaining bits are the uncompressed format.
    h.point_format = p[field::point_format];
    if ((h.point_format & 0xC0) != 0 && (h.point_format & 0x3F) <= 10) {
        h.compressed = true;
        h.point_format &= 0x3F;
    }
    h.record_length = load<std::uint16_t>(p + field::record_length);
    h.point_count = load<std::uint32_t>(p + field::legacy_point_count);
    for (int k = 0; k < 3; ++k) {
        h.scale[k] = load<double>(p + field::scale + 8 * k);
        h.offset[k] = load<double>(p + field::offset + 8 * k);
        h.max[k] = load<double>(p + field::bounds + 16 * k);
        h.min[k] = load<double>(p + field::bounds + 16 * k + 8);
    }
    check_layout(file, h);  // guarantees the 1.4 fields below lie inside the declared header
    if (h.minor >= 4) {
        h.evlr_start = load<std::uint64_t>(p + field::evlr_start);
        h.evlr_count = load<std::uint32_t>(p + field::evlr_count);
        // The 64-bit count is authoritative in 1.4; some writers leave it 0 for small files.
        const std::uint64_t count64 = load<std::uint64_t>(p + field::point_count);
        if (count64 != 0) h.point_count = count64;
    }
    check_point_format(file, h.point_format, h.record_length);
    check_scale_offset(file, h);
    if (!h.compressed) check_point_count(file, h);  // LAZ counts are checked against the chunk table
    h.raw = file.read(0, h.header_size, "header");
    return h;
}

// The records this reader uses: CRS records (kept verbatim) and the Extra Bytes description.
bool is_wanted_record(const RawVlr& r) {
    return r.user_id == kProjectionUser || (r.user_id == kSpecUser && r.record_id == kExtraBytesRecord) ||
           (r.user_id == kLaszipUser && r.record_id == kLaszipRecord) || r.user_id == kCopcUser;
}

std::string record_label(std::size_t index, std::size_t count, const std::string& user, std::uint16_t id) {
    return std::to_string(index + 1) + " of " + std::to_string(count) + " ('" + user + "', record " + std::to_string(id) + ")";
}

std::vector<RawVlr> read_vlrs(InputFile& file, const LasHeader& h, bool keep_all = false) {
    const std::size_t region_size = h.offset_to_points - h.header_size;
    if (h.vlr_count > region_size / kVlrHeaderSize)
        file.fail("header declares " + std::to_string(h.vlr_count) + " VLRs, but only " + std::to_string(region_size) +
                  " bytes lie between the header and the point data (each VLR needs at least 54)");
    const Bytes region = file.read(h.header_size, region_size, "variable-length records");
    std::vector<RawVlr> records;
    std::size_t pos = 0;
    for (std::size_t i = 0; i < h.vlr_count; ++i) {
        if (region_size - pos < kVlrHeaderSize)
            file.fail("VLR " + std::to_string(i + 1) + " of " + std::to_string(h.vlr_count) + " starts at byte " +
                      std::to_string(h.header_size + pos) + ", past the start of point data at byte " + std::to_string(h.offset_to_points));
        const std::uint8_t* p = region.data() + pos;
        RawVlr record{load_string(p + 2, 16), load<std::uint16_t>(p + 18), load_string(p + 22, 32), {}};
        const std::size_t length = load<std::uint16_t>(p + 20);
        if (length > region_size - pos - kVlrHeaderSize)
            file.fail("VLR " + record_label(i, h.vlr_count, record.user_id, record.record_id) + " at byte " +
                      std::to_string(h.header_size + pos) + " declares " + std::to_string(length) +
                      " bytes and runs past the start of point data at byte " + std::to_string(h.offset_to_points));
        if (keep_all || is_wanted_record(record)) {
            record.data.assign(p + kVlrHeaderSize, p + kVlrHeaderSize + length);
            records.push_back(std::move(record));
        }
        pos += kVlrHeaderSize + length;
    }
    return records;
}

// LAS 1.4 extended VLRs live after the point data and may be large (WKT, waveforms); only the
// wanted ones are loaded, the others are skipped by seeking.
std::vector<RawVlr> read_evlrs(InputFile& file, const LasHeader& h, bool keep_all = false) {
    std::vector<RawVlr> records;
    if (h.minor < 4 || h.evlr_count == 0) return records;
    if (h.evlr_start < h.header_size || h.evlr_start > file.size() || h.evlr_count > (file.size() - h.evlr_start) / kEvlrHeaderSize)
        file.fail("header declares " + std::to_string(h.evlr_count) + " extended VLRs from byte " + std::to_string(h.evlr_start) +
                  ", which does not fit in the file (" + std::to_string(file.size()) + " bytes; truncated?)");
    std::uint64_t pos = h.evlr_start;
    for (std::size_t i = 0; i < h.evlr_count; ++i) {
        const Bytes head = file.read(pos, kEvlrHeaderSize, "extended VLR header");
        RawVlr record{load_string(head.data() + 2, 16), load<std::uint16_t>(head.data() + 18), load_string(head.data() + 28, 32), {}};
        const std::uint64_t length = load<std::uint64_t>(head.data() + 20);
        if (length > file.size() - pos - kEvlrHeaderSize)
            file.fail("extended VLR " + record_label(i, h.evlr_count, record.user_id, record.record_id) + " at byte " +
                      std::to_string(pos) + " declares " + std::to_string(length) +
                      " bytes and runs past the end of the file (truncated?)");
        if (keep_all || is_wanted_record(record)) {
            record.data = file.read(pos + kEvlrHeaderSize, static_cast<std::size_t>(length), "extended VLR");
            records.push_back(std::move(record));
        }
        pos += kEvlrHeaderSize + length;
    }
    return records;
}

// One documented Extra Bytes attribute and where it sits in the point record.
struct ExtraField {
    ExtraAttribute attribute;  // name, type, description, no_data (in value units); no values yet
    int data_type = 0;         // LAS code 1..10
    std::size_t offset = 0;    // byte offset within the point record
    bool scaled = false;
    double scale = 1.0, add = 0.0;  // value = raw * scale + add
};

double load_raw_extra(const std::uint8_t* p, int data_type) {
    switch (data_type) {
        case 1:
            return p[0];
        case 2:
            return static_cast<std::int8_t>(p[0]);
        case 3:
            return load<std::uint16_t>(p);
        case 4:
            return load<std::int16_t>(p);
        case 5:
            return load<std::uint32_t>(p);
        case 6:
            return load<std::int32_t>(p);
        case 7:
            return static_cast<double>(load<std::uint64_t>(p));
        case 8:
            return static_cast<double>(load<std::int64_t>(p));
        case 9:
            return load<float>(p);
        case 10:
            return load<double>(p);
        default:
            return 0;
    }
}

// no_data/min/max are "anytype": upcast to 8 bytes as uint64, int64 or double by the base type.
double load_anytype(const std::uint8_t* p, AttributeType type) {
    if (is_float_type(type)) return load<double>(p);
    if (is_unsigned_type(type)) return static_cast<double>(load<std::uint64_t>(p));
    return static_cast<double>(load<std::int64_t>(p));
}

// Descriptor layout: reserved[2], data_type, options, name[32], unused[4], no_data[3x8],
// min[3x8], max[3x8], scale[3 doubles], offset[3 doubles], description[32].
ExtraField parse_descriptor(const InputFile& file, const std::uint8_t* d, std::size_t index, std::size_t offset) {
    enum : std::uint8_t { kNoData = 1, kScale = 8, kOffset = 16 };
    ExtraField f;
    f.data_type = d[2];
    f.offset = offset;
    const std::uint8_t options = d[3];
    f.attribute.name = load_string(d + 4, 32);
    if (f.attribute.name.empty()) f.attribute.name = "extra_" + std::to_string(index + 1);
    f.attribute.description = load_string(d + 160, 32);
    f.attribute.type = attribute_type_of(f.data_type);
    if (options & kScale) f.scale = load<double>(d + 112);
    if (options & kOffset) f.add = load<double>(d + 136);
    if (!std::isfinite(f.scale) || f.scale == 0 || !std::isfinite(f.add))
        file.fail("Extra Bytes attribute '" + f.attribute.name + "' has scale " + number_text(f.scale) + " and offset " +
                  number_text(f.add) + ", expected a finite non-zero scale and a finite offset");
    f.scaled = f.scale != 1.0 || f.add != 0.0;
    // Scaled integers hold real numbers in memory; keeping the integer type would round them
    // away on write (ExtraAttribute has no scale of its own).
    if (f.scaled) f.attribute.type = AttributeType::Float64;
    if (options & kNoData) {
        const double raw = load_anytype(d + 40, attribute_type_of(f.data_type));
        f.attribute.no_data = f.scaled ? raw * f.scale + f.add : raw;
    }
    return f;
}

// Byte size of a descriptor's field; 0 when the data type is unknown (> 30).
std::size_t descriptor_field_size(int data_type, std::uint8_t options) {
    if (data_type == 0) return options;  // undocumented bytes: options holds their count
    if (data_type <= 10) return base_type_size(data_type);
    if (data_type <= 30) return base_type_size((data_type - 1) % 10 + 1) * (data_type <= 20 ? 2 : 3);  // deprecated arrays
    return 0;
}

std::vector<ExtraField> parse_extra_bytes(const InputFile& file, const RawVlr& record, const PointFormat& format,
                                          std::size_t record_length) {
    std::vector<ExtraField> fields;
    if (record.data.size() % kExtraBytesDescriptorSize != 0)
        log_warn(file.name() + ": Extra Bytes record is " + std::to_string(record.data.size()) +
                 " bytes, not a multiple of 192; the incomplete descriptor is ignored");
    const std::size_t count = record.data.size() / kExtraBytesDescriptorSize;
    std::size_t offset = format.size;
    for (std::size_t i = 0; i < count; ++i) {
        const std::uint8_t* d = record.data.data() + i * kExtraBytesDescriptorSize;
        const int data_type = d[2];
        const std::size_t size = descriptor_field_size(data_type, d[3]);
        if (size == 0 && data_type != 0) {
            log_warn(file.name() + ": Extra Bytes attribute '" + load_string(d + 4, 32) + "' has unknown data type " +
                     std::to_string(data_type) + "; it and the attributes after it are ignored");
            break;
        }
        if (size > record_length - offset)
            file.fail("Extra Bytes attribute '" + load_string(d + 4, 32) + "' ends at byte " + std::to_string(offset + size) +
                      " of the point record, but records are only " + std::to_string(record_length) + " bytes long");
        if (data_type >= 1 && data_type <= 10)
            fields.push_back(parse_descriptor(file, d, i, offset));
        else if (data_type > 10)
            log_warn(file.name() + ": Extra Bytes attribute '" + load_string(d + 4, 32) + "' uses a deprecated array type and is skipped");
        offset += size;
    }
    return fields;
}

std::vector<ExtraField> find_extra_fields(const InputFile& file, const std::vector<RawVlr>& records, const PointFormat& format,
                                          std::size_t record_length) {
    for (const RawVlr& r : records)
        if (r.user_id == kSpecUser && r.record_id == kExtraBytesRecord) return parse_extra_bytes(file, r, format, record_length);
    return {};
}

// From a GeoKeyDirectory: "EPSG:nnnn" from ProjectedCSTypeGeoKey (3072), else
// GeographicTypeGeoKey (2048), empty when neither holds an EPSG code (32767 means user-defined);
// and the EPSG codes of the linear and vertical units (ProjLinearUnitsGeoKey 3076,
// VerticalUnitsGeoKey 4099; 0 when absent), which a code alone does not tell without the registry.
void read_geokeys(const Bytes& data, Georeference& georef) {
    if (data.size() < 8) return;
    const std::size_t declared = load<std::uint16_t>(data.data() + 6);
    const std::size_t count = std::min(declared, data.size() / 8 - 1);
    int projected = 0, geographic = 0;
    for (std::size_t k = 1; k <= count; ++k) {
        const std::uint8_t* key = data.data() + 8 * k;
        const std::uint16_t id = load<std::uint16_t>(key), location = load<std::uint16_t>(key + 2);
        const std::uint16_t value = load<std::uint16_t>(key + 6);
        if (location != 0) continue;  // value stored elsewhere: not a plain code
        if (id == 3072) projected = value;
        if (id == 2048) geographic = value;
        if (id == 3076) georef.linear_unit_code = value;
        if (id == 4099) georef.vertical_unit_code = value;
    }
    const int code = projected > 0 && projected < 32767 ? projected : geographic;
    if (georef.crs_wkt.empty() && code > 0 && code < 32767) georef.crs_wkt = "EPSG:" + std::to_string(code);
}

Georeference georeference_from(const std::vector<RawVlr>& records) {
    Georeference georef;
    for (const RawVlr& r : records) {
        if (r.user_id != kProjectionUser) continue;
        georef.las_vlrs.push_back(r);
        if (r.record_id == kWktRecord && georef.crs_wkt.empty()) georef.crs_wkt = load_string(r.data.data(), r.data.size());
    }
    for (const RawVlr& r : georef.las_vlrs)
        if (r.record_id == kGeoKeyDirectoryRecord) read_geokeys(r.data, georef);
    return georef;
}

// Float keeps ~0.25 mm steps below 4096 m, so the origin must bring every point that close.
// Prefer the header offset (then local = X * scale exactly), else 0 for small coordinates, else
// the centre of the bounds rounded to a whole metre.
double choose_origin_axis(double offset, double lo, double hi) {
    constexpr double kMaxLocal = 4096.0;
    auto reach = [&](double origin) { return std::max(std::abs(lo - origin), std::abs(hi - origin)); };
    if (reach(offset) <= kMaxLocal) return offset + 0.0;  // + 0.0 turns an offset of -0 into 0
    if (reach(0.0) <= kMaxLocal) return 0.0;
    return std::round((lo + hi) / 2);
}

Eigen::Vector3d choose_origin(InputFile& file, const LasHeader& h, std::uint64_t first_record) {
    if (h.point_count == 0) return h.offset;
    Eigen::Vector3d lo = h.min, hi = h.max;
    // Header bounds are required by the specification but not always right; fall back to the
    // first point when they are unusable.
    const bool usable = lo.allFinite() && hi.allFinite() && (lo.array() <= hi.array()).all() &&
                        lo.cwiseAbs().maxCoeff() <= kMaxCoordinate && hi.cwiseAbs().maxCoeff() <= kMaxCoordinate;
    if (!usable) {
        const Bytes first = file.read(first_record, 12, "first point record");
        for (int k = 0; k < 3; ++k) lo[k] = hi[k] = load<std::int32_t>(first.data() + 4 * k) * h.scale[k] + h.offset[k];
    }
    Eigen::Vector3d origin;
    for (int k = 0; k < 3; ++k) origin[k] = choose_origin_axis(h.offset[k], lo[k], hi[k]);
    return origin;
}

// Bytes a PointCloud holds per point of this format: position, intensity, returns and class,
// GPS time and colour when the format has them, one double per extra-bytes field.
std::uint64_t cloud_bytes_per_point(const PointFormat& format, const std::vector<ExtraField>& fields) {
    std::uint64_t bytes = sizeof(Eigen::Vector3f) + sizeof(std::uint16_t) + 3 * sizeof(std::uint8_t);
    if (format.gps_offset >= 0) bytes += sizeof(double);
    if (format.rgb_offset >= 0) bytes += 3 * sizeof(std::uint16_t);
    return bytes + fields.size() * sizeof(double);
}

// Sizes the attribute vectors the point format has (and only those).
// With `all_fields` false only positions, return numbers, classification and extras.
void allocate_attributes(PointCloud& cloud, const PointFormat& format, const std::vector<ExtraField>& fields, std::size_t n,
                         bool all_fields) {
    cloud.positions.resize(n);
    cloud.return_number.resize(n);
    cloud.number_of_returns.resize(n);
    cloud.classification.resize(n);
    if (all_fields) {
        cloud.intensity.resize(n);
        if (format.gps_offset >= 0) cloud.gps_time.resize(n);
        if (format.rgb_offset >= 0) cloud.rgb.resize(n);
    }
    for (const ExtraField& f : fields) {
        cloud.extras.push_back(f.attribute);
        cloud.extras.back().values.resize(n);
    }
}

struct PointDecoder {
    const PointFormat& format;
    Eigen::Vector3d scale, offset, origin;
    const std::vector<ExtraField>& fields;
    bool all_fields = true;
    const Box3d* bounds = nullptr;  // when set, inside[i] says whether point i lies in it
    std::vector<std::uint8_t>* inside = nullptr;

    void decode(const std::uint8_t* record, std::size_t i, PointCloud& cloud) const {
        Eigen::Vector3d global;
        for (int k = 0; k < 3; ++k) {
            global[k] = load<std::int32_t>(record + 4 * k) * scale[k] + offset[k];
            cloud.positions[i][k] = static_cast<float>(global[k] - origin[k]);
        }
        if (bounds) (*inside)[i] = bounds->contains(global) ? 1 : 0;
        if (all_fields) cloud.intensity[i] = load<std::uint16_t>(record + 12);
        const std::uint8_t returns = record[14];
        if (format.extended) {
            cloud.return_number[i] = returns & 0x0f;
            cloud.number_of_returns[i] = returns >> 4;
            cloud.classification[i] = record[16];
        } else {
            cloud.return_number[i] = returns & 0x07;
            cloud.number_of_returns[i] = (returns >> 3) & 0x07;
            cloud.classification[i] = record[15] & 0x1f;  // upper bits are synthetic/key-point/withheld flags
        }
        if (all_fields && format.gps_offset >= 0) cloud.gps_time[i] = load<double>(record + format.gps_offset);
        if (all_fields && format.rgb_offset >= 0)
            for (int c = 0; c < 3; ++c) cloud.rgb[i][c] = load<std::uint16_t>(record + format.rgb_offset + 2 * c);
        for (std::size_t e = 0; e < fields.size(); ++e) {
            const ExtraField& f = fields[e];
            const double raw = load_raw_extra(record + f.offset, f.data_type);
            cloud.extras[e].values[i] = f.scaled ? raw * f.scale + f.add : raw;
        }
    }
};

// ---------------------------------------------------------------------------------------------
// Point records, uncompressed or LAZ

// A LAS or LAZ file opened for reading points: header, records and, for LAZ, where the chunks are.
struct LasSource {
    LasHeader header;
    std::vector<RawVlr> records;  // VLRs first (vlr_count of them), then EVLRs
    std::size_t vlr_count = 0;
    std::optional<laz::LaszipVlr> laz;
    std::vector<laz::Chunk> chunks;  // LAZ: every chunk, in file order
    std::optional<laz::CopcInfo> copc;
};

const RawVlr* find_record(const std::vector<RawVlr>& records, std::string_view user, std::uint16_t id) {
    for (const RawVlr& r : records)
        if (r.user_id == user && r.record_id == id) return &r;
    return nullptr;
}

// Point data ends where the EVLRs start (LAS 1.4) or at the end of the file.
std::uint64_t point_data_end(const InputFile& file, const LasHeader& h) {
    if (h.minor >= 4 && h.evlr_count > 0 && h.evlr_start > h.offset_to_points && h.evlr_start <= file.size()) return h.evlr_start;
    return file.size();
}

LasSource open_las(InputFile& file, bool keep_all_records) {
    LasSource src;
    src.header = read_header(file);
    const LasHeader& h = src.header;
    src.records = read_vlrs(file, h, keep_all_records);
    src.vlr_count = src.records.size();
    for (RawVlr& r : read_evlrs(file, h, keep_all_records)) src.records.push_back(std::move(r));
    if (!h.compressed) return src;
    const RawVlr* laszip = find_record(src.records, kLaszipUser, kLaszipRecord);
    if (!laszip) file.fail("the point format byte marks LAZ compression, but there is no LASzip VLR ('laszip encoded', record 22204)");
    src.laz = laz::parse_laszip_vlr(laszip->data, h.point_format, h.record_length, file.name());
    src.chunks = laz::read_chunk_table(file, *src.laz, h.offset_to_points, point_data_end(file, h), h.point_count, h.record_length);
    if (const RawVlr* info = find_record(src.records, kCopcUser, kCopcInfoRecord)) src.copc = laz::parse_copc_info(info->data, file.name());
    return src;
}

// Where the first point record's bytes are: LAZ stores each chunk's first point raw.
std::uint64_t first_record_offset(const LasSource& src) {
    return src.chunks.empty() ? src.header.offset_to_points : src.chunks.front().offset;
}

// Receives `count` consecutive records starting at point `first`. LAZ chunks are decoded in
// parallel, so a sink must accept calls for disjoint ranges from several threads.
using RecordSink = std::function<void(std::size_t first, std::size_t count, const std::uint8_t* records)>;

void read_uncompressed_records(InputFile& file, const LasHeader& h, const RecordSink& sink) {
    const std::size_t n = static_cast<std::size_t>(h.point_count);
    const std::size_t per_block = std::max<std::size_t>(1, kChunkBytes / h.record_length);
    Bytes buffer;
    for (std::size_t first = 0; first < n; first += per_block) {
        const std::size_t count = std::min(per_block, n - first);
        buffer.resize(count * h.record_length);
        file.read(h.offset_to_points + std::uint64_t{first} * h.record_length, buffer.size(), buffer.data(), "point data");
        sink(first, count, buffer.data());
    }
}

// Chunks are independent: TBB decodes them in parallel, each task holding one chunk's
// compressed and decoded bytes, so memory stays bounded by (threads x chunk size).
void decode_laz_chunks(InputFile& file, const LasSource& src, const std::vector<laz::Chunk>& chunks, const laz::LayerSelection& selection,
                       const RecordSink& sink) {
    const std::uint16_t record_length = src.header.record_length;
    treelobes::parallel_for(tbb::blocked_range<std::size_t>(0, chunks.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
        Bytes compressed, records;
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const laz::Chunk& chunk = chunks[i];
            compressed.resize(static_cast<std::size_t>(chunk.bytes));
            file.read(chunk.offset, compressed.size(), compressed.data(), "LAZ chunk " + std::to_string(i));
            records.resize(static_cast<std::size_t>(chunk.count) * record_length);
            laz::decode_chunk(*src.laz, record_length, compressed, static_cast<std::size_t>(chunk.count), records.data(), selection,
                              file.name(), i);
            sink(static_cast<std::size_t>(chunk.first_point), static_cast<std::size_t>(chunk.count), records.data());
        }
    });
}

void read_records(InputFile& file, const LasSource& src, const std::vector<laz::Chunk>& chunks, const laz::LayerSelection& selection,
                  const RecordSink& sink) {
    if (src.header.compressed)
        decode_laz_chunks(file, src, chunks, selection, sink);
    else
        read_uncompressed_records(file, src.header, sink);
}

// The COPC octree: levels and nodes for `info`, and the nodes a bounds query must decode
// (renumbered so that their points are consecutive).
std::vector<laz::Chunk> describe_copc(InputFile& file, const LasSource& src, const std::optional<Box3d>& bounds, SourceFormat& source) {
    const std::vector<laz::CopcNode> nodes = laz::read_copc_hierarchy(file, *src.copc);
    std::vector<laz::Chunk> selected;
    std::uint64_t first = 0;
    source.copc_levels = 0;
    for (const laz::CopcNode& node : nodes) {
        source.copc_levels = std::max(source.copc_levels, node.level + 1);
        if (bounds && !bounds->intersects(node.min, node.max)) continue;
        laz::Chunk chunk = node.chunk;
        chunk.first_point = first;
        first += chunk.count;
        selected.push_back(chunk);
    }
    source.copc_nodes = nodes.size();
    source.copc_nodes_read = selected.size();
    return selected;
}

SourceFormat source_format_of(const LasSource& src) {
    const LasHeader& h = src.header;
    SourceFormat source;
    source.format = "las";
    source.version = "1." + std::to_string(h.minor);
    source.las_point_format = h.point_format;
    source.las_scale = h.scale;
    source.las_offset = h.offset;
    if (src.laz) {
        source.laz = true;
        source.laz_chunk_size = src.laz->chunk_size;
        source.laz_chunks = src.chunks.size();
    }
    return source;
}

PointCloud read_las_from(InputFile& file, const CloudReadOptions& options) {
    const LasSource src = open_las(file, false);
    const LasHeader& header = src.header;
    const PointFormat& format = kFormats[static_cast<std::size_t>(header.point_format)];
    const std::vector<ExtraField> fields = find_extra_fields(file, src.records, format, header.record_length);
    check_memory_estimate(header.point_count * cloud_bytes_per_point(format, fields), file.name(),
                          "the header's " + std::to_string(header.point_count) + " points");

    PointCloud cloud;
    cloud.source = source_format_of(src);
    cloud.georef = georeference_from(src.records);
    cloud.origin = choose_origin(file, header, first_record_offset(src));
    std::vector<laz::Chunk> chunks = src.chunks;
    if (src.copc) {
        std::vector<laz::Chunk> selected = describe_copc(file, src, options.bounds, cloud.source);
        if (options.bounds) chunks = std::move(selected);  // only the nodes that meet the box
    }
    std::uint64_t n = header.point_count;
    if (header.compressed) {
        n = 0;
        for (const laz::Chunk& c : chunks) n += c.count;
    }
    const bool all_fields = !options.xyz_classification_only;
    allocate_attributes(cloud, format, fields, static_cast<std::size_t>(n), all_fields);
    std::vector<std::uint8_t> inside;
    if (options.bounds) inside.assign(static_cast<std::size_t>(n), 0);
    const PointDecoder decoder{
            format, header.scale, header.offset, cloud.origin, fields, all_fields, options.bounds ? &*options.bounds : nullptr, &inside};
    const laz::LayerSelection selection =
            all_fields ? laz::LayerSelection::all() : laz::LayerSelection::xyz_classification(!fields.empty());
    read_records(file, src, chunks, selection, [&](std::size_t first, std::size_t count, const std::uint8_t* records) {
        for (std::size_t j = 0; j < count; ++j) decoder.decode(records + j * header.record_length, first + j, cloud);
    });
    if (options.bounds) {
        cloud = cloud.subset(std::vector<bool>(inside.begin(), inside.end()));
    }
    return cloud;
}

LasRecords read_records_from(InputFile& file) {
    const LasSource src = open_las(file, true);
    const LasHeader& h = src.header;
    LasRecords out;
    out.header = h.raw;
    out.minor = h.minor;
    out.point_format = h.point_format;
    out.record_length = h.record_length;
    out.point_count = h.point_count;
    out.compressed = h.compressed;
    out.vlrs.assign(src.records.begin(), src.records.begin() + static_cast<std::ptrdiff_t>(src.vlr_count));
    out.evlrs.assign(src.records.begin() + static_cast<std::ptrdiff_t>(src.vlr_count), src.records.end());
    out.points.resize(static_cast<std::size_t>(h.point_count) * h.record_length);
    read_records(file, src, src.chunks, laz::LayerSelection::all(), [&](std::size_t first, std::size_t count, const std::uint8_t* records) {
        std::memcpy(out.points.data() + first * h.record_length, records, count * h.record_length);
    });
    return out;
}

// ---------------------------------------------------------------------------------------------
// Writing

struct WritePlan {
    int minor = 2;
    const PointFormat* format = &kFormats[0];
    std::size_t record_length = 0;
    Eigen::Vector3d scale{0.001, 0.001, 0.001}, offset{0, 0, 0};
    std::vector<std::size_t> extra_offsets;  // byte offset of cloud.extras[k] in a record
    std::vector<RawVlr> vlrs, evlrs;
    std::uint16_t global_encoding = 0;
};

bool from_las(const PointCloud& cloud) { return cloud.source.format == "las"; }

// Formats 0-5 hold 3-bit return numbers and 5-bit classes; larger values need formats 6-10.
bool needs_extended_fields(const PointCloud& cloud) {
    auto any_above = [](const std::vector<std::uint8_t>& v, int limit) {
        return std::any_of(v.begin(), v.end(), [&](std::uint8_t x) { return x > limit; });
    };
    return any_above(cloud.classification, 31) || any_above(cloud.return_number, 7) || any_above(cloud.number_of_returns, 7);
}

// The input's format, with waveform formats mapped to their base (waveform packets are not
// kept, so writing a waveform format would describe data that is not there).
int source_point_format(const PointCloud& cloud) {
    const int f = cloud.source.las_point_format;
    if (!from_las(cloud) || f < 0 || f > 10) return -1;
    static constexpr std::array<int, 11> without_waveform = {0, 1, 2, 3, 1, 3, 6, 7, 8, 6, 8};
    return without_waveform[static_cast<std::size_t>(f)];
}

// Keeps the input's format when it holds every attribute present; otherwise the smallest format
// that does. Without a LAS source: 0, 1 (GPS time), 2 (RGB) or 3 (both).
int choose_point_format(const PointCloud& cloud) {
    const bool gps = !cloud.gps_time.empty(), rgb = !cloud.rgb.empty();
    int f = source_point_format(cloud);
    if (f < 0) f = gps ? (rgb ? 3 : 1) : (rgb ? 2 : 0);
    if (needs_extended_fields(cloud) && f < 6) f = rgb || kFormats[static_cast<std::size_t>(f)].rgb_offset >= 0 ? 7 : 6;
    if (rgb && kFormats[static_cast<std::size_t>(f)].rgb_offset < 0) f = f == 0 ? 2 : f == 1 ? 3 : 7;
    if (gps && kFormats[static_cast<std::size_t>(f)].gps_offset < 0) f = f == 0 ? 1 : 3;
    return f;
}

int source_minor_version(const PointCloud& cloud) {
    const std::string& v = cloud.source.version;
    if (!from_las(cloud) || v.size() != 3 || v[0] != '1' || v[1] != '.' || v[2] < '0' || v[2] > '4') return -1;
    return v[2] - '0';
}

bool has_record(const std::vector<RawVlr>& records, std::string_view user, std::uint16_t id) {
    return std::any_of(records.begin(), records.end(), [&](const RawVlr& r) { return r.user_id == user && r.record_id == id; });
}

// Whether the CRS is written as a new WKT record: it came as WKT text from elsewhere (a PLY
// sidecar, `convert --to-metres`) rather than as LAS records, and is not a bare EPSG code.
bool writes_new_wkt_record(const PointCloud& cloud) {
    const std::string& wkt = cloud.georef.crs_wkt;
    return !wkt.empty() && !wkt.starts_with("EPSG:") && !has_record(cloud.georef.las_vlrs, kProjectionUser, kWktRecord);
}

// The input's version (1.2 without a LAS source), raised to what the format needs; 1.4 for
// Extra Bytes (DESIGN.md: tree ids go in a LAS 1.4 Extra Bytes attribute), EVLRs, more than
// 2^32 - 1 points and a new WKT record (LAS defines the CRS as WKT, with the global encoding's
// WKT bit, from 1.4 on).
int choose_minor_version(const PointCloud& cloud, int format, bool has_evlrs) {
    int minor = source_minor_version(cloud);
    if (minor < 0) minor = 2;
    minor = std::max(minor, minimum_minor_version(format));
    if (!cloud.extras.empty() || has_evlrs || cloud.size() > std::numeric_limits<std::uint32_t>::max() || writes_new_wkt_record(cloud))
        minor = 4;
    return minor;
}

void store_anytype(std::uint8_t* p, AttributeType type, double value) {
    if (is_float_type(type))
        store<double>(p, value);
    else if (is_unsigned_type(type))
        store<std::uint64_t>(p, saturate<std::uint64_t>(value));
    else
        store<std::int64_t>(p, saturate<std::int64_t>(value));
}

Bytes extra_bytes_descriptor(const ExtraAttribute& attribute, const std::string& file) {
    if (attribute.name.empty() || attribute.name.size() > 32)
        throw Error::input(file, "extra attribute name '" + attribute.name + "' cannot be stored in LAS Extra Bytes (1-32 bytes expected)");
    Bytes d(kExtraBytesDescriptorSize, 0);
    d[2] = static_cast<std::uint8_t>(las_data_type(attribute.type));
    store_string(d.data() + 4, 32, attribute.name);
    if (attribute.no_data) {
        d[3] = 1;  // no_data bit
        store_anytype(d.data() + 40, attribute.type, *attribute.no_data);
    }
    store_string(d.data() + 160, 31, attribute.description);  // < 32 bytes keeps a terminating NUL
    return d;
}

RawVlr extra_bytes_vlr(const std::vector<ExtraAttribute>& extras, const std::string& file) {
    RawVlr record{std::string(kSpecUser), kExtraBytesRecord, "Extra Bytes", {}};
    for (const ExtraAttribute& attribute : extras) {
        const Bytes d = extra_bytes_descriptor(attribute, file);
        record.data.insert(record.data.end(), d.begin(), d.end());
    }
    return record;
}

// Extra Bytes description (rebuilt from cloud.extras), the CRS records unchanged, and a WKT
// record when the CRS came from elsewhere (PLY sidecar) as WKT text rather than as LAS records.
std::vector<RawVlr> records_to_write(const PointCloud& cloud, const std::string& file) {
    std::vector<RawVlr> records;
    if (!cloud.extras.empty()) records.push_back(extra_bytes_vlr(cloud.extras, file));
    for (const RawVlr& r : cloud.georef.las_vlrs)
        if (!(r.user_id == kSpecUser && r.record_id == kExtraBytesRecord)) records.push_back(r);
    if (writes_new_wkt_record(cloud)) {
        const std::string& wkt = cloud.georef.crs_wkt;
        RawVlr record{std::string(kProjectionUser), kWktRecord, "OGC coordinate system WKT", {}};
        record.data.assign(wkt.begin(), wkt.end());
        record.data.push_back(0);
        records.push_back(std::move(record));
    }
    return records;
}

// Records too long for a VLR's 16-bit length become LAS 1.4 extended VLRs.
void split_records(std::vector<RawVlr> records, WritePlan& plan) {
    for (RawVlr& r : records) {
        if (r.data.size() > std::numeric_limits<std::uint16_t>::max())
            plan.evlrs.push_back(std::move(r));
        else
            plan.vlrs.push_back(std::move(r));
    }
}

// Adjusted standard GPS time (seconds since the GPS epoch minus 1e9) versus GPS week time (0 to
// 604800 s): the cloud does not keep the input's flag, so it is recovered from the values.
bool uses_adjusted_gps_time(const PointCloud& cloud) {
    return std::any_of(cloud.gps_time.begin(), cloud.gps_time.end(), [](double t) { return t < 0 || t >= 604800.0; });
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> global_bounds(const PointCloud& cloud, const std::string& file) {
    Eigen::Vector3d lo = cloud.origin, hi = cloud.origin;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!cloud.positions[i].allFinite())
            throw Error::input(file, "point " + std::to_string(i) + " has a NaN/inf coordinate, which LAS cannot store");
        const Eigen::Vector3d p = cloud.global(i);
        if (i == 0) lo = hi = p;
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    return {lo, hi};
}

bool fits_int32(double lo, double hi, double offset, double scale) {
    constexpr double limit = 2147483647.0 - 1.0;  // margin for rounding
    const double a = (lo - offset) / scale, b = (hi - offset) / scale;
    return std::abs(a) <= limit && std::abs(b) <= limit;
}

// Scale: the input's, else 1 mm. Offset: the input's, else the origin rounded to a metre; when
// the coordinates do not fit in 32-bit integers around it (moved or merged clouds), the centre.
void choose_frame(const PointCloud& cloud, const std::string& file, WritePlan& plan) {
    const auto [lo, hi] = global_bounds(cloud, file);
    const bool keep = from_las(cloud);
    static constexpr const char* axes[] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
        const double s = cloud.source.las_scale[k], o = cloud.source.las_offset[k];
        plan.scale[k] = keep && std::isfinite(s) && s > 0 ? s : 0.001;
        plan.offset[k] = keep && std::isfinite(o) ? o : std::round(cloud.origin[k]);
        if (!std::isfinite(plan.offset[k])) plan.offset[k] = 0;
        if (fits_int32(lo[k], hi[k], plan.offset[k], plan.scale[k])) continue;
        plan.offset[k] = std::round((lo[k] + hi[k]) / 2);
        if (!fits_int32(lo[k], hi[k], plan.offset[k], plan.scale[k]))
            throw Error::input(file, std::string("coordinates span ") + std::to_string(hi[k] - lo[k]) + " m in " + axes[k] +
                                             ", too much for LAS 32-bit integers at scale " + std::to_string(plan.scale[k]));
    }
}

WritePlan plan_write(const PointCloud& cloud, const std::string& file) {
    WritePlan plan;
    split_records(records_to_write(cloud, file), plan);
    const int format = choose_point_format(cloud);
    plan.format = &kFormats[static_cast<std::size_t>(format)];
    plan.minor = choose_minor_version(cloud, format, !plan.evlrs.empty());
    plan.record_length = plan.format->size;
    for (const ExtraAttribute& attribute : cloud.extras) {
        plan.extra_offsets.push_back(plan.record_length);
        plan.record_length += attribute_type_size(attribute.type);
    }
    if (plan.record_length > std::numeric_limits<std::uint16_t>::max())
        throw Error::input(file, "point records of " + std::to_string(plan.record_length) +
                                         " bytes exceed the LAS limit of 65535 (too many extra attributes)");
    if (uses_adjusted_gps_time(cloud)) plan.global_encoding |= kGpsAdjustedStandardTime;
    if (plan.minor >= 4 && (has_record(plan.vlrs, kProjectionUser, kWktRecord) || has_record(plan.evlrs, kProjectionUser, kWktRecord)))
        plan.global_encoding |= kWktCrs;
    choose_frame(cloud, file, plan);
    return plan;
}

std::array<std::int32_t, 3> quantize(const PointCloud& cloud, std::size_t i, const WritePlan& plan) {
    std::array<std::int32_t, 3> q{};
    for (int k = 0; k < 3; ++k) {
        const double global = cloud.origin[k] + static_cast<double>(cloud.positions[i][k]);
        q[static_cast<std::size_t>(k)] = static_cast<std::int32_t>(std::llround((global - plan.offset[k]) / plan.scale[k]));
    }
    return q;
}

struct Returns {
    std::uint8_t number, count;
};

// Absent return numbers are written as "first of one return", which validators accept (0 is not
// a valid return number).
Returns returns_of(const PointCloud& cloud, std::size_t i, bool extended) {
    const int limit = extended ? 15 : 7;
    const int number = cloud.return_number.empty() ? 1 : cloud.return_number[i];
    const int count = cloud.number_of_returns.empty() ? std::max(number, 1) : cloud.number_of_returns[i];
    return {static_cast<std::uint8_t>(std::min(number, limit)), static_cast<std::uint8_t>(std::min(count, limit))};
}

// What the header must say about the points: bounds of the written coordinates and points per
// return number.
struct PointStats {
    Eigen::Vector3d min{0, 0, 0}, max{0, 0, 0};
    std::array<std::uint64_t, 16> by_return{};  // index = return number
};

PointStats point_stats(const PointCloud& cloud, const WritePlan& plan) {
    PointStats stats;
    std::array<std::int32_t, 3> lo{}, hi{};
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto q = quantize(cloud, i, plan);
        for (std::size_t k = 0; k < 3; ++k) {
            lo[k] = i == 0 ? q[k] : std::min(lo[k], q[k]);
            hi[k] = i == 0 ? q[k] : std::max(hi[k], q[k]);
        }
        ++stats.by_return[returns_of(cloud, i, plan.format->extended).number];
    }
    for (int k = 0; k < 3; ++k) {
        const auto u = static_cast<std::size_t>(k);
        stats.min[k] = cloud.empty() ? 0 : lo[u] * plan.scale[k] + plan.offset[k];
        stats.max[k] = cloud.empty() ? 0 : hi[u] * plan.scale[k] + plan.offset[k];
    }
    return stats;
}

// The header's creation date is today's, unless SOURCE_DATE_EPOCH (the reproducible-builds
// convention: seconds since 1970 UTC) pins it, so that regenerated files are byte-identical.
std::chrono::sys_days creation_date() {
    using namespace std::chrono;
    if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH")) {
        char* end = nullptr;
        const long long seconds = std::strtoll(epoch, &end, 10);
        if (end != epoch && *end == '\0' && seconds >= 0) return floor<days>(sys_seconds{std::chrono::seconds{seconds}});
    }
    return floor<days>(system_clock::now());
}

std::pair<std::uint16_t, std::uint16_t> creation_day_and_year() {
    using namespace std::chrono;
    const sys_days today = creation_date();
    const year_month_day date{today};
    const sys_days january_first{date.year() / January / 1};
    return {static_cast<std::uint16_t>((today - january_first).count() + 1), static_cast<std::uint16_t>(int(date.year()))};
}

struct Placement {
    std::uint64_t point_count = 0;
    std::uint32_t offset_to_points = 0;
    std::uint64_t evlr_start = 0;
};

void store_counts(std::uint8_t* h, const WritePlan& plan, const PointStats& stats, std::uint64_t n) {
    // Legacy 32-bit counts stay 0 in 1.4 files when they cannot describe the points.
    const bool legacy = plan.format->id < 6 && n <= std::numeric_limits<std::uint32_t>::max();
    store<std::uint32_t>(h + field::legacy_point_count, legacy ? static_cast<std::uint32_t>(n) : 0);
    for (std::size_t r = 1; r <= 5; ++r)
        store<std::uint32_t>(h + field::legacy_by_return + 4 * (r - 1), legacy ? static_cast<std::uint32_t>(stats.by_return[r]) : 0);
    if (plan.minor < 4) return;
    store<std::uint64_t>(h + field::point_count, n);
    for (std::size_t r = 1; r <= 15; ++r) store<std::uint64_t>(h + field::by_return + 8 * (r - 1), stats.by_return[r]);
}

Bytes header_bytes(const WritePlan& plan, const PointStats& stats, const Placement& place) {
    Bytes h(header_size_for(plan.minor), 0);
    std::uint8_t* p = h.data();
    std::memcpy(p, "LASF", 4);
    store<std::uint16_t>(p + field::global_encoding, plan.global_encoding);
    p[field::version_major] = 1;
    p[field::version_minor] = static_cast<std::uint8_t>(plan.minor);
    store_string(p + field::system_id, 32, "treelobes");
    store_string(p + field::software, 32, std::string("treelobes ") + kVersion);
    const auto [day, year] = creation_day_and_year();
    store<std::uint16_t>(p + field::creation_day, day);
    store<std::uint16_t>(p + field::creation_year, year);
    store<std::uint16_t>(p + field::header_size, static_cast<std::uint16_t>(h.size()));
    store<std::uint32_t>(p + field::offset_to_points, place.offset_to_points);
    store<std::uint32_t>(p + field::vlr_count, static_cast<std::uint32_t>(plan.vlrs.size()));
    p[field::point_format] = static_cast<std::uint8_t>(plan.format->id);
    store<std::uint16_t>(p + field::record_length, static_cast<std::uint16_t>(plan.record_length));
    store_counts(p, plan, stats, place.point_count);
    for (int k = 0; k < 3; ++k) {
        store<double>(p + field::scale + 8 * k, plan.scale[k]);
        store<double>(p + field::offset + 8 * k, plan.offset[k]);
        store<double>(p + field::bounds + 16 * k, stats.max[k]);
        store<double>(p + field::bounds + 16 * k + 8, stats.min[k]);
    }
    if (plan.minor >= 3) store<std::uint64_t>(p + field::waveform_start, 0);
    if (plan.minor >= 4) {
        store<std::uint64_t>(p + field::evlr_start, plan.evlrs.empty() ? 0 : place.evlr_start);
        store<std::uint32_t>(p + field::evlr_count, static_cast<std::uint32_t>(plan.evlrs.size()));
    }
    return h;
}

Bytes record_header(const RawVlr& r, bool extended) {
    Bytes h(extended ? kEvlrHeaderSize : kVlrHeaderSize, 0);
    store_string(h.data() + 2, 16, r.user_id);
    store<std::uint16_t>(h.data() + 18, r.record_id);
    if (extended)
        store<std::uint64_t>(h.data() + 20, r.data.size());
    else
        store<std::uint16_t>(h.data() + 20, static_cast<std::uint16_t>(r.data.size()));
    store_string(h.data() + (extended ? 28 : 22), 32, r.description);
    return h;
}

void write_bytes(std::ostream& out, const Bytes& bytes) {
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

void write_records(std::ostream& out, const std::vector<RawVlr>& records, bool extended) {
    for (const RawVlr& r : records) {
        write_bytes(out, record_header(r, extended));
        write_bytes(out, r.data);
    }
}

void store_extra_value(std::uint8_t* p, const ExtraAttribute& attribute, double value) {
    // Integer types cannot hold NaN: the declared no-data value stands in for it.
    if (std::isnan(value) && attribute.no_data && !is_float_type(attribute.type)) value = *attribute.no_data;
    switch (attribute.type) {
        case AttributeType::UInt8:
            store<std::uint8_t>(p, saturate<std::uint8_t>(value));
            break;
        case AttributeType::Int8:
            store<std::int8_t>(p, saturate<std::int8_t>(value));
            break;
        case AttributeType::UInt16:
            store<std::uint16_t>(p, saturate<std::uint16_t>(value));
            break;
        case AttributeType::Int16:
            store<std::int16_t>(p, saturate<std::int16_t>(value));
            break;
        case AttributeType::UInt32:
            store<std::uint32_t>(p, saturate<std::uint32_t>(value));
            break;
        case AttributeType::Int32:
            store<std::int32_t>(p, saturate<std::int32_t>(value));
            break;
        case AttributeType::UInt64:
            store<std::uint64_t>(p, saturate<std::uint64_t>(value));
            break;
        case AttributeType::Int64:
            store<std::int64_t>(p, saturate<std::int64_t>(value));
            break;
        case AttributeType::Float32: {
            // double -> float outside float's range is undefined; IEEE overflow gives infinity.
            constexpr double max = std::numeric_limits<float>::max();
            constexpr float infinity = std::numeric_limits<float>::infinity();
            const float f = std::abs(value) > max ? (value > 0 ? infinity : -infinity) : static_cast<float>(value);
            store<float>(p, f);
            break;
        }
        case AttributeType::Float64:
            store<double>(p, value);
            break;
    }
}

void encode_point(std::uint8_t* record, const PointCloud& cloud, std::size_t i, const WritePlan& plan) {
    const PointFormat& format = *plan.format;
    const auto q = quantize(cloud, i, plan);
    for (std::size_t k = 0; k < 3; ++k) store<std::int32_t>(record + 4 * k, q[k]);
    if (!cloud.intensity.empty()) store<std::uint16_t>(record + 12, cloud.intensity[i]);
    const Returns r = returns_of(cloud, i, format.extended);
    const std::uint8_t cls = cloud.classification.empty() ? 0 : cloud.classification[i];
    if (format.extended) {
        record[14] = static_cast<std::uint8_t>(r.number | (r.count << 4));
        record[16] = cls;
    } else {
        record[14] = static_cast<std::uint8_t>(r.number | (r.count << 3));
        record[15] = static_cast<std::uint8_t>(cls & 0x1f);
    }
    if (format.gps_offset >= 0 && !cloud.gps_time.empty()) store<double>(record + format.gps_offset, cloud.gps_time[i]);
    if (format.rgb_offset >= 0 && !cloud.rgb.empty())
        for (std::size_t c = 0; c < 3; ++c) store<std::uint16_t>(record + format.rgb_offset + 2 * c, cloud.rgb[i][c]);
    for (std::size_t e = 0; e < cloud.extras.size(); ++e)
        store_extra_value(record + plan.extra_offsets[e], cloud.extras[e], cloud.extras[e].values[i]);
}

void write_points(std::ostream& out, const PointCloud& cloud, const WritePlan& plan) {
    const std::size_t per_chunk = std::max<std::size_t>(1, kChunkBytes / plan.record_length);
    Bytes buffer;
    for (std::size_t first = 0; first < cloud.size(); first += per_chunk) {
        const std::size_t count = std::min(per_chunk, cloud.size() - first);
        buffer.assign(count * plan.record_length, 0);
        for (std::size_t j = 0; j < count; ++j) encode_point(buffer.data() + j * plan.record_length, cloud, first + j, plan);
        write_bytes(out, buffer);
    }
}

Placement placement_of(const WritePlan& plan, std::size_t n, const std::string& file) {
    Placement place;
    place.point_count = n;
    std::uint64_t offset = header_size_for(plan.minor);
    for (const RawVlr& r : plan.vlrs) offset += kVlrHeaderSize + r.data.size();
    if (offset > std::numeric_limits<std::uint32_t>::max())
        throw Error::input(file, "the " + std::to_string(plan.vlrs.size()) + " VLRs do not fit before the point data (4 GiB limit)");
    place.offset_to_points = static_cast<std::uint32_t>(offset);
    place.evlr_start = offset + std::uint64_t{n} * plan.record_length;
    return place;
}

}  // namespace

PointCloud read_las(const fs::path& path, const CloudReadOptions& options) {
    InputFile file(path);
    return read_las_from(file, options);
}

PointCloud read_las_buffer(std::span<const std::uint8_t> bytes, const std::string& name, const CloudReadOptions& options) {
    InputFile file(bytes, name);
    return read_las_from(file, options);
}

LasRecords read_las_records(const fs::path& path) {
    InputFile file(path);
    return read_records_from(file);
}

LasRecords read_las_records(std::span<const std::uint8_t> bytes, const std::string& name) {
    InputFile file(bytes, name);
    return read_records_from(file);
}

// The uncompressed twin: same header fields, minus the LAZ marks and the records that only
// describe compressed data; offsets recomputed for the records that remain.
void write_las_records(const LasRecords& records, const fs::path& path) {
    auto describes_compression = [](const RawVlr& r) {
        return (r.user_id == kLaszipUser && r.record_id == kLaszipRecord) || r.user_id == kCopcUser;
    };
    std::vector<RawVlr> vlrs, evlrs;
    std::copy_if(records.vlrs.begin(), records.vlrs.end(), std::back_inserter(vlrs),
                 [&](const RawVlr& r) { return !describes_compression(r); });
    std::copy_if(records.evlrs.begin(), records.evlrs.end(), std::back_inserter(evlrs),
                 [&](const RawVlr& r) { return !describes_compression(r); });
    Bytes header = records.header;
    std::uint64_t offset = header.size();
    for (const RawVlr& r : vlrs) offset += kVlrHeaderSize + r.data.size();
    if (offset > 0xFFFFFFFFull) throw Error::input(path.string(), "VLRs too large for a LAS header");
    header[field::point_format] = static_cast<std::uint8_t>(records.point_format);
    store<std::uint32_t>(header.data() + field::offset_to_points, static_cast<std::uint32_t>(offset));
    store<std::uint32_t>(header.data() + field::vlr_count, static_cast<std::uint32_t>(vlrs.size()));
    if (records.minor >= 4 && header.size() >= kHeaderSize14) {
        const std::uint64_t evlr_start = evlrs.empty() ? 0 : offset + records.points.size();
        store<std::uint64_t>(header.data() + field::evlr_start, evlr_start);
        store<std::uint32_t>(header.data() + field::evlr_count, static_cast<std::uint32_t>(evlrs.size()));
    }
    write_atomically(path, [&](std::ostream& out) {
        write_bytes(out, header);
        write_records(out, vlrs, false);
        write_bytes(out, records.points);
        write_records(out, evlrs, true);
    });
}

// Version and point format: the input's when the cloud came from LAS and the format still holds
// every attribute, else the smallest that does (0-3 in LAS 1.2; 6/7 in 1.4 for classes > 31 or
// more than 7 returns); LAS 1.4 whenever there are extra attributes. Coordinates are quantised
// with the input's scale/offset (else 1 mm around the rounded origin); extra attributes are
// described in an Extra Bytes VLR with their declared types; CRS records are written back
// unchanged. Header bounds and per-return counts describe the written points.
void write_las(const PointCloud& cloud, const fs::path& path) {
    const std::string file = path.string();
    cloud.check_consistent(file);
    const WritePlan plan = plan_write(cloud, file);
    const PointStats stats = point_stats(cloud, plan);
    const Placement place = placement_of(plan, cloud.size(), file);
    write_atomically(path, [&](std::ostream& out) {
        write_bytes(out, header_bytes(plan, stats, place));
        write_records(out, plan.vlrs, false);
        write_points(out, cloud, plan);
        write_records(out, plan.evlrs, true);
    });
}

}  // namespace treelobes
