// LAS reader/writer on synthetic clouds: round trips per point format, Extra Bytes, CRS records,
// UTM-sized coordinates, header contents, and malformed files (each must give Error with exit
// code InvalidInput, never a crash or a huge allocation).
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace treelobes;
using treelobes::test::error_code_of;
using treelobes::test::TempDir;

namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes load_file(const std::filesystem::path& path) {
    const std::string text = read_file(path);
    return {text.begin(), text.end()};
}

void save_file(const std::filesystem::path& path, const Bytes& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// Test files are written on little-endian hosts, like LAS itself.
template <typename T>
void poke(Bytes& bytes, std::size_t offset, T value) {
    ASSERT_LE(offset + sizeof(T), bytes.size());
    std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

template <typename T>
T peek(const Bytes& bytes, std::size_t offset) {
    T value{};
    std::memcpy(&value, bytes.data() + offset, sizeof(T));
    return value;
}

std::size_t find_text(const Bytes& bytes, const std::string& text) {
    const auto it = std::search(bytes.begin(), bytes.end(), text.begin(), text.end());
    return it == bytes.end() ? std::string::npos : static_cast<std::size_t>(it - bytes.begin());
}

// Byte offset of the k-th Extra Bytes descriptor (the VLR data follows its 54-byte header, whose
// user id starts at byte 2).
std::size_t descriptor_offset(const Bytes& bytes, std::size_t k) {
    const std::size_t user = find_text(bytes, "LASF_Spec");
    EXPECT_NE(user, std::string::npos);
    return user - 2 + 54 + 192 * k;
}

bool format_has_gps(int f) { return f == 1 || f == 3 || f >= 6; }
bool format_has_rgb(int f) { return f == 2 || f == 3 || f == 7 || f == 8; }

// A cloud as if read from a LAS file of point format `format`, with every attribute it holds.
PointCloud cloud_of_format(int format, std::size_t n = 50) {
    PointCloud cloud;
    cloud.source.format = "las";
    cloud.source.version = format >= 6 ? "1.4" : "1.2";
    cloud.source.las_point_format = format;
    cloud.source.las_scale = {0.001, 0.001, 0.001};
    cloud.source.las_offset = {0, 0, 0};
    const int max_returns = format >= 6 ? 15 : 7;
    for (std::size_t i = 0; i < n; ++i) {
        const float t = static_cast<float>(i);
        cloud.positions.emplace_back(0.125f * t, -0.5f * t, 3.0f + 0.01f * t);
        cloud.intensity.push_back(static_cast<std::uint16_t>(i * 1000));
        const int count = 1 + static_cast<int>(i % static_cast<std::size_t>(max_returns));
        cloud.number_of_returns.push_back(static_cast<std::uint8_t>(count));
        cloud.return_number.push_back(static_cast<std::uint8_t>(1 + i % static_cast<std::size_t>(count)));
        cloud.classification.push_back(static_cast<std::uint8_t>(format >= 6 ? (i * 7) % 256 : (i * 3) % 32));
        if (format_has_gps(format)) cloud.gps_time.push_back(3.1e8 + 0.25 * static_cast<double>(i));
        if (format_has_rgb(format)) cloud.rgb.push_back({static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(65535 - i), 1234});
    }
    return cloud;
}

void expect_same_points(const PointCloud& expected, const PointCloud& actual, double tolerance) {
    ASSERT_EQ(expected.size(), actual.size());
    for (std::size_t i = 0; i < expected.size(); ++i)
        ASSERT_LE((expected.global(i) - actual.global(i)).cwiseAbs().maxCoeff(), tolerance) << "point " << i;
}

PointCloud write_then_read(const PointCloud& cloud, const TempDir& dir, const std::string& name = "cloud.las") {
    write_las(cloud, dir / name);
    return read_las(dir / name);
}

// A small LAS 1.4 file with two extra attributes and a CRS record, used by the corruption tests.
Bytes small_file_with_extras(const TempDir& dir) {
    PointCloud cloud = cloud_of_format(1, 4);
    cloud.add_extra("a", AttributeType::Int16).values = {1, 2, -3, 4};
    cloud.add_extra("b", AttributeType::Float64).values = {0.5, 1.5, 2.5, 3.5};
    cloud.georef.las_vlrs.push_back({"LASF_Projection", 2112, "WKT", {'G', 'E', 'O', 'G', 'C', 'S', '[', ']', 0}});
    write_las(cloud, dir / "small.las");
    return load_file(dir / "small.las");
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// Round trips

class LasPointFormat : public ::testing::TestWithParam<int> {};

TEST_P(LasPointFormat, RoundTripKeepsFormatAndAttributes) {
    TempDir dir;
    const int format = GetParam();
    const PointCloud cloud = cloud_of_format(format);
    const PointCloud back = write_then_read(cloud, dir);
    EXPECT_EQ(back.source.format, "las");
    EXPECT_EQ(back.source.las_point_format, format);
    EXPECT_EQ(back.source.version, cloud.source.version);
    expect_same_points(cloud, back, 0.0005);
    EXPECT_EQ(back.intensity, cloud.intensity);
    EXPECT_EQ(back.return_number, cloud.return_number);
    EXPECT_EQ(back.number_of_returns, cloud.number_of_returns);
    EXPECT_EQ(back.classification, cloud.classification);
    EXPECT_EQ(back.gps_time, cloud.gps_time);
    EXPECT_EQ(back.rgb, cloud.rgb);
    EXPECT_TRUE(back.extras.empty());
}

INSTANTIATE_TEST_SUITE_P(Formats, LasPointFormat, ::testing::Values(0, 1, 2, 3, 6, 7, 8));

TEST(LasWrite, ChoosesSmallestFormatForTheAttributesPresent) {
    TempDir dir;
    PointCloud cloud;
    cloud.positions = {{0, 0, 0}, {1, 2, 3}};
    auto written = [&] {
        const PointCloud back = write_then_read(cloud, dir);
        return std::to_string(back.source.las_point_format) + "/" + back.source.version;
    };
    EXPECT_EQ(written(), "0/1.2");
    cloud.gps_time = {1.0, 2.0};
    EXPECT_EQ(written(), "1/1.2");
    cloud.rgb = {{{1, 2, 3}}, {{4, 5, 6}}};
    EXPECT_EQ(written(), "3/1.2");
    cloud.gps_time.clear();
    EXPECT_EQ(written(), "2/1.2");
    cloud.classification = {2, 40};  // classes above 31 need the 1.4 formats
    EXPECT_EQ(written(), "7/1.4");
    cloud.rgb.clear();
    EXPECT_EQ(written(), "6/1.4");
    cloud.classification = {2, 5};
    cloud.return_number = {1, 9};  // so do more than 7 returns
    EXPECT_EQ(written(), "6/1.4");
}

TEST(LasWrite, KeepsSourceFormatAndUpgradesOnlyWhenNeeded) {
    TempDir dir;
    PointCloud cloud = cloud_of_format(1, 3);
    cloud.source.version = "1.0";
    EXPECT_EQ(write_then_read(cloud, dir).source.version, "1.0");
    cloud.source.version = "1.3";
    EXPECT_EQ(write_then_read(cloud, dir).source.version, "1.3");
    cloud.rgb = {{{1, 2, 3}}, {{4, 5, 6}}, {{7, 8, 9}}};  // format 1 has no RGB -> 3
    const PointCloud back = write_then_read(cloud, dir);
    EXPECT_EQ(back.source.las_point_format, 3);
    EXPECT_EQ(back.rgb, cloud.rgb);
    cloud.source.las_point_format = 5;  // waveform packets are not kept: written as format 3
    EXPECT_EQ(write_then_read(cloud, dir).source.las_point_format, 3);
}

TEST(LasWrite, AbsentReturnNumbersBecomeSingleReturns) {
    TempDir dir;
    PointCloud cloud;
    cloud.positions = {{0, 0, 0}, {1, 1, 1}};
    const PointCloud back = write_then_read(cloud, dir);
    EXPECT_EQ(back.return_number, (std::vector<std::uint8_t>{1, 1}));
    EXPECT_EQ(back.number_of_returns, (std::vector<std::uint8_t>{1, 1}));
    EXPECT_EQ(back.classification, (std::vector<std::uint8_t>{0, 0}));
    EXPECT_TRUE(back.gps_time.empty());
    EXPECT_TRUE(back.rgb.empty());
}

TEST(LasWrite, EmptyCloudRoundTrips) {
    TempDir dir;
    PointCloud cloud;
    const PointCloud back = write_then_read(cloud, dir);
    EXPECT_EQ(back.size(), 0u);
    EXPECT_EQ(back.source.las_point_format, 0);
}

TEST(LasWrite, SourceDateEpochPinsTheCreationDate) {
    TempDir dir;
    const PointCloud cloud = cloud_of_format(1, 3);
    ::setenv("SOURCE_DATE_EPOCH", "1740787200", 1);  // 2025-03-01 00:00 UTC: day 60 of 2025
    write_las(cloud, dir / "first.las");
    write_las(cloud, dir / "second.las");
    ::unsetenv("SOURCE_DATE_EPOCH");
    const Bytes first = load_file(dir / "first.las");
    EXPECT_EQ(peek<std::uint16_t>(first, 90), 60);
    EXPECT_EQ(peek<std::uint16_t>(first, 92), 2025);
    EXPECT_EQ(first, load_file(dir / "second.las"));
}

// ------------------------------------------------------------------------------------------------
// Extra Bytes

TEST(LasExtras, Int32TreeIdAndFloat64RoundTripAsLas14) {
    TempDir dir;
    PointCloud cloud = cloud_of_format(1, 5);
    {
        ExtraAttribute& tree = cloud.add_extra("treeID", AttributeType::Int32);
        tree.values = {0, 1, 2, 2, -7};
        tree.description = "tree id, 0 = no tree";
    }  // add_extra may reallocate: no reference is kept across calls
    ExtraAttribute& height = cloud.add_extra("height", AttributeType::Float64);
    height.values = {0.125, -1e-9, 1e300, -9999, 42};
    height.no_data = -9999;

    const PointCloud back = write_then_read(cloud, dir);
    EXPECT_EQ(back.source.version, "1.4");
    EXPECT_EQ(back.source.las_point_format, 1);
    ASSERT_EQ(back.extras.size(), 2u);
    const ExtraAttribute* t = back.extra("treeID");
    ASSERT_NE(t, nullptr);
    EXPECT_EQ(t->type, AttributeType::Int32);
    EXPECT_EQ(t->values, cloud.extra("treeID")->values);
    EXPECT_EQ(t->description, "tree id, 0 = no tree");
    EXPECT_FALSE(t->no_data.has_value());
    const ExtraAttribute* h = back.extra("height");
    ASSERT_NE(h, nullptr);
    EXPECT_EQ(h->type, AttributeType::Float64);
    EXPECT_EQ(h->values, height.values);
    ASSERT_TRUE(h->no_data.has_value());
    EXPECT_EQ(*h->no_data, -9999);
    expect_same_points(cloud, back, 0.0005);
    EXPECT_EQ(back.gps_time, cloud.gps_time);
}

TEST(LasExtras, EveryDataTypeRoundTripsAndSaturates) {
    TempDir dir;
    PointCloud cloud;
    cloud.positions = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
    const std::vector<std::pair<AttributeType, std::vector<double>>> cases = {
            {AttributeType::UInt8, {0, 255, 300}},
            {AttributeType::Int8, {-128, 127, -1000}},
            {AttributeType::UInt16, {0, 65535, -5}},
            {AttributeType::Int16, {-32768, 32767, 1.6}},
            {AttributeType::UInt32, {0, 4294967295.0, 7}},
            {AttributeType::Int32, {-2147483648.0, 2147483647.0, -2.4}},
            {AttributeType::UInt64, {0, 9007199254740992.0, 1e30}},
            {AttributeType::Int64, {-9007199254740992.0, 9007199254740992.0, -1e30}},
            {AttributeType::Float32, {0.5f, -3.25e10f, 1e300}},
            {AttributeType::Float64, {0.1, -1e-300, 1e300}},
    };
    for (const auto& [type, values] : cases) cloud.add_extra(attribute_type_name(type), type).values = values;
    const PointCloud back = write_then_read(cloud, dir);
    const std::vector<std::vector<double>> expected = {
            {0, 255, 255},
            {-128, 127, -128},
            {0, 65535, 0},
            {-32768, 32767, 2},
            {0, 4294967295.0, 7},
            {-2147483648.0, 2147483647.0, -2},
            {0, 9007199254740992.0, 18446744073709551615.0},
            {-9007199254740992.0, 9007199254740992.0, -9223372036854775808.0},
            {0.5, -3.25e10f, std::numeric_limits<double>::infinity()},
            {0.1, -1e-300, 1e300},
    };
    ASSERT_EQ(back.extras.size(), cases.size());
    for (std::size_t k = 0; k < cases.size(); ++k) {
        EXPECT_EQ(back.extras[k].name, attribute_type_name(cases[k].first));
        EXPECT_EQ(back.extras[k].type, cases[k].first);
        EXPECT_EQ(back.extras[k].values, expected[k]) << back.extras[k].name;
    }
}

TEST(LasExtras, NanInIntegerAttributeIsWrittenAsNoData) {
    TempDir dir;
    PointCloud cloud;
    cloud.positions = {{0, 0, 0}, {1, 1, 1}};
    ExtraAttribute& id = cloud.add_extra("treeID", AttributeType::Int32);
    id.values = {std::nan(""), 3};
    id.no_data = -1;
    const PointCloud back = write_then_read(cloud, dir);
    EXPECT_EQ(back.extra("treeID")->values, (std::vector<double>{-1, 3}));
    EXPECT_EQ(back.extra("treeID")->no_data, -1.0);
}

TEST(LasExtras, ScaleOffsetAndNoDataFromTheDescriptorAreApplied) {
    TempDir dir;
    Bytes bytes = small_file_with_extras(dir);
    const std::size_t descriptor = descriptor_offset(bytes, 0);
    ASSERT_EQ(bytes[descriptor + 2], 4);  // int16
    bytes[descriptor + 3] |= 1 | 8 | 16;  // no_data, scale, offset
    poke<std::int64_t>(bytes, descriptor + 40, -3);
    poke<double>(bytes, descriptor + 112, 0.5);
    poke<double>(bytes, descriptor + 136, 10.0);
    save_file(dir / "scaled.las", bytes);
    const PointCloud cloud = read_las(dir / "scaled.las");
    const ExtraAttribute* a = cloud.extra("a");
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(a->type, AttributeType::Float64);  // scaled integers hold real numbers
    EXPECT_EQ(a->values, (std::vector<double>{10.5, 11, 8.5, 12}));
    EXPECT_EQ(a->no_data, 8.5);
    EXPECT_EQ(cloud.extra("b")->values, (std::vector<double>{0.5, 1.5, 2.5, 3.5}));
}

TEST(LasExtras, UndocumentedBytesAreSkipped) {
    TempDir dir;
    Bytes bytes = small_file_with_extras(dir);
    const std::size_t descriptor = descriptor_offset(bytes, 0);
    bytes[descriptor + 2] = 0;  // undocumented ...
    bytes[descriptor + 3] = 2;  // ... 2 bytes
    save_file(dir / "undocumented.las", bytes);
    const PointCloud cloud = read_las(dir / "undocumented.las");
    ASSERT_EQ(cloud.extras.size(), 1u);
    EXPECT_EQ(cloud.extras[0].name, "b");
    EXPECT_EQ(cloud.extras[0].values, (std::vector<double>{0.5, 1.5, 2.5, 3.5}));
}

TEST(LasExtras, RecordsLongerThanTheFormatWithoutDescriptionReadFine) {
    TempDir dir;
    Bytes bytes = small_file_with_extras(dir);
    const std::size_t user = find_text(bytes, "LASF_Spec");
    ASSERT_NE(user, std::string::npos);
    bytes[user + 8] = 'X';  // no longer the Extra Bytes VLR
    save_file(dir / "plain.las", bytes);
    const PointCloud cloud = read_las(dir / "plain.las");
    EXPECT_TRUE(cloud.extras.empty());
    expect_same_points(cloud_of_format(1, 4), cloud, 0.0005);
}

TEST(LasExtras, DescriptionsAreTruncatedAndLongNamesRejected) {
    TempDir dir;
    PointCloud cloud;
    cloud.positions = {{0, 0, 0}};
    cloud.add_extra("x", AttributeType::UInt8).description = std::string(40, 'd');
    EXPECT_EQ(write_then_read(cloud, dir).extra("x")->description, std::string(31, 'd'));
    cloud.add_extra(std::string(33, 'n'), AttributeType::UInt8);
    EXPECT_EQ(error_code_of([&] { write_las(cloud, dir / "long.las"); }), ExitCode::InvalidInput);
    EXPECT_FALSE(std::filesystem::exists(dir / "long.las"));
}

// ------------------------------------------------------------------------------------------------
// CRS records

TEST(LasGeoref, GeoTiffRecordsPassThroughUnchanged) {
    TempDir dir;
    PointCloud cloud = cloud_of_format(0, 3);
    // GeoKeyDirectory: version 1.1.0, 2 keys: ProjectedCSTypeGeoKey = 32632, ProjLinearUnits = 9001.
    const std::vector<std::uint16_t> keys = {1, 1, 0, 2, 3072, 0, 1, 32632, 3076, 0, 1, 9001};
    RawVlr directory{"LASF_Projection", 34735, "GeoKeyDirectoryTag", {}};
    for (std::uint16_t k : keys) {
        directory.data.push_back(static_cast<std::uint8_t>(k & 0xff));
        directory.data.push_back(static_cast<std::uint8_t>(k >> 8));
    }
    const RawVlr ascii{"LASF_Projection", 34737, "GeoAsciiParamsTag", {'W', 'G', 'S', ' ', '8', '4', '|', 0}};
    cloud.georef.las_vlrs = {directory, ascii};
    const PointCloud back = write_then_read(cloud, dir);
    ASSERT_EQ(back.georef.las_vlrs.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(back.georef.las_vlrs[k].user_id, cloud.georef.las_vlrs[k].user_id);
        EXPECT_EQ(back.georef.las_vlrs[k].record_id, cloud.georef.las_vlrs[k].record_id);
        EXPECT_EQ(back.georef.las_vlrs[k].description, cloud.georef.las_vlrs[k].description);
        EXPECT_EQ(back.georef.las_vlrs[k].data, cloud.georef.las_vlrs[k].data);
    }
    EXPECT_EQ(back.georef.crs_wkt, "EPSG:32632");
    EXPECT_EQ(back.georef.linear_unit_code, 9001);  // ProjLinearUnits: metre
    EXPECT_EQ(back.georef.vertical_unit_code, 0);   // not declared
    EXPECT_EQ(back.source.version, "1.2");
}

TEST(LasGeoref, WktRecordSetsTheCrs) {
    TempDir dir;
    PointCloud cloud = cloud_of_format(6, 3);
    const std::string wkt = "PROJCS[\"WGS 84 / UTM zone 32N\"]";
    RawVlr record{"LASF_Projection", 2112, "OGC WKT", {wkt.begin(), wkt.end()}};
    record.data.push_back(0);
    cloud.georef.las_vlrs = {record};
    write_las(cloud, dir / "wkt.las");
    const Bytes bytes = load_file(dir / "wkt.las");
    EXPECT_EQ(peek<std::uint16_t>(bytes, 6) & 16, 16);  // global encoding: WKT CRS
    const PointCloud back = read_las(dir / "wkt.las");
    EXPECT_EQ(back.georef.crs_wkt, wkt);
    ASSERT_EQ(back.georef.las_vlrs.size(), 1u);
    EXPECT_EQ(back.georef.las_vlrs[0].data, record.data);
}

TEST(LasGeoref, CrsTextWithoutRecordsIsWrittenAsWkt) {
    TempDir dir;
    PointCloud cloud = cloud_of_format(0, 3);
    cloud.georef.crs_wkt = "GEOGCS[\"WGS 84\"]";  // e.g. from a PLY georef sidecar
    const PointCloud back = write_then_read(cloud, dir);
    EXPECT_EQ(back.georef.crs_wkt, cloud.georef.crs_wkt);
    EXPECT_EQ(back.source.version, "1.4");  // LAS defines a WKT CRS from 1.4 on
    cloud.georef.crs_wkt = "EPSG:25832";  // not WKT: no record is made up
    EXPECT_TRUE(write_then_read(cloud, dir).georef.las_vlrs.empty());
}

TEST(LasGeoref, RecordsLongerThan64KiBBecomeExtendedVlrs) {
    TempDir dir;
    PointCloud cloud = cloud_of_format(1, 3);
    std::string wkt = "COMPD_CS[\"" + std::string(70000, 'x') + "\"]";
    RawVlr record{"LASF_Projection", 2112, "OGC WKT", {wkt.begin(), wkt.end()}};
    record.data.push_back(0);
    cloud.georef.las_vlrs = {record};
    const PointCloud back = write_then_read(cloud, dir);
    EXPECT_EQ(back.source.version, "1.4");
    EXPECT_EQ(back.georef.crs_wkt, wkt);
    ASSERT_EQ(back.georef.las_vlrs.size(), 1u);
    EXPECT_EQ(back.georef.las_vlrs[0].data, record.data);
    expect_same_points(cloud, back, 0.0005);
}

// ------------------------------------------------------------------------------------------------
// Coordinates and header

TEST(LasCoordinates, UtmSizedCoordinatesSurviveWriteRead) {
    TempDir dir;
    PointCloud cloud;
    cloud.origin = {650000.0, 5800000.0, 120.0};
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> spread(-400.0f, 400.0f);
    // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
    // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
    for (int i = 0; i < 1000; ++i) {
        const float z = spread(rng) / 10, y = spread(rng), x = spread(rng);
        cloud.positions.emplace_back(x, y, z);
    }
    const PointCloud back = write_then_read(cloud, dir);
    expect_same_points(cloud, back, 0.001);
    // Local coordinates stay small, so float keeps sub-millimetre steps.
    EXPECT_LT(back.positions[0].cwiseAbs().maxCoeff(), 4096.0f);
    // Again through a LAS source at 1 mm with offset 0 (as in lidR's MixedConifer.las): x fits
    // in 32-bit integers around offset 0 and is read back with an origin near the data; y
    // (5.8e9 mm) does not fit and gets a new offset.
    PointCloud zero_offset = back;
    zero_offset.source.las_offset = {0, 0, 0};
    zero_offset.source.las_scale = {0.001, 0.001, 0.001};
    const PointCloud again = write_then_read(zero_offset, dir, "again.las");
    expect_same_points(cloud, again, 0.001);
    EXPECT_LT((again.origin - cloud.origin).cwiseAbs().maxCoeff(), 1000.0);
}

TEST(LasCoordinates, CoordinatesOutsideTheSourceFrameGetANewOffset) {
    TempDir dir;
    PointCloud cloud = cloud_of_format(0, 3);
    cloud.origin = {6.5e5, 5.8e6, 0};  // moved far from the source offset 0 at scale 1 mm
    const PointCloud back = write_then_read(cloud, dir);
    expect_same_points(cloud, back, 0.0005);
}

TEST(LasHeader, BoundsAndReturnCountsDescribeThePoints) {
    TempDir dir;
    PointCloud cloud;
    cloud.origin = {1000, 2000, 0};
    cloud.positions = {{-1.5f, 2, 3}, {4, -5.25f, 6}, {0.5f, 0.5f, -7}};
    cloud.return_number = {1, 2, 2};
    cloud.number_of_returns = {2, 2, 3};
    write_las(cloud, dir / "h.las");
    const Bytes h = load_file(dir / "h.las");
    EXPECT_DOUBLE_EQ(peek<double>(h, 179), 1004.0);  // max x
    EXPECT_DOUBLE_EQ(peek<double>(h, 187), 998.5);   // min x
    EXPECT_DOUBLE_EQ(peek<double>(h, 195), 2002.0);
    EXPECT_DOUBLE_EQ(peek<double>(h, 203), 1994.75);
    EXPECT_DOUBLE_EQ(peek<double>(h, 211), 6.0);
    EXPECT_DOUBLE_EQ(peek<double>(h, 219), -7.0);
    EXPECT_EQ(peek<std::uint32_t>(h, 107), 3u);
    EXPECT_EQ(peek<std::uint32_t>(h, 111), 1u);  // first returns
    EXPECT_EQ(peek<std::uint32_t>(h, 115), 2u);  // second returns
    EXPECT_EQ(peek<std::uint32_t>(h, 119), 0u);
    EXPECT_EQ(h.size(), 227u + 3u * 20u);
}

TEST(LasHeader, Las14CountsAre64Bit) {
    TempDir dir;
    PointCloud cloud = cloud_of_format(6, 20);
    write_las(cloud, dir / "h.las");
    const Bytes h = load_file(dir / "h.las");
    EXPECT_EQ(h[25], 4);
    EXPECT_EQ(peek<std::uint16_t>(h, 94), 375);
    EXPECT_EQ(peek<std::uint32_t>(h, 107), 0u);  // legacy count is 0 for formats 6-10
    EXPECT_EQ(peek<std::uint64_t>(h, 247), 20u);
    std::uint64_t total = 0;
    for (int r = 0; r < 15; ++r) total += peek<std::uint64_t>(h, 255 + 8 * static_cast<std::size_t>(r));
    EXPECT_EQ(total, 20u);
    EXPECT_EQ(peek<std::uint16_t>(h, 6) & 1, 1);  // adjusted standard GPS time (values > 1 week)
}

TEST(LasWrite, NonFiniteCoordinatesAndMissingFolderAreErrors) {
    TempDir dir;
    PointCloud cloud;
    cloud.positions = {{0, 0, 0}, {std::nanf(""), 1, 1}};
    EXPECT_EQ(error_code_of([&] { write_las(cloud, dir / "nan.las"); }), ExitCode::InvalidInput);
    cloud.positions[1] = {1, 1, 1};
    EXPECT_EQ(error_code_of([&] { write_las(cloud, dir / "missing" / "x.las"); }), ExitCode::InvalidInput);
    cloud.intensity = {1};  // inconsistent attribute length
    EXPECT_EQ(error_code_of([&] { write_las(cloud, dir / "bad.las"); }), ExitCode::InvalidInput);
}

// ------------------------------------------------------------------------------------------------
// Malformed input

class LasBadInput : public ::testing::Test {
protected:
    void SetUp() override { good = small_file_with_extras(dir); }

    // Writes the mutated bytes and expects read_las to fail with InvalidInput, naming the file.
    void expect_rejected(const Bytes& bytes, const std::string& fragment) {
        save_file(dir / "bad.las", bytes);
        try {
            read_las(dir / "bad.las");
            ADD_FAILURE() << "no error for a file that should give '" << fragment << "'";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput);
            const std::string message = e.what();
            EXPECT_NE(message.find("bad.las"), std::string::npos) << message;
            EXPECT_NE(message.find(fragment), std::string::npos) << message;
            EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        }
    }

    TempDir dir;
    Bytes good;
};

TEST_F(LasBadInput, EmptyFile) { expect_rejected({}, "empty"); }

TEST_F(LasBadInput, DirectoryAndMissingFile) {
    EXPECT_EQ(error_code_of([&] { read_las(dir.path()); }), ExitCode::InvalidInput);
    EXPECT_EQ(error_code_of([&] { read_las(dir / "nope.las"); }), ExitCode::InvalidInput);
}

TEST_F(LasBadInput, BadSignature) {
    Bytes bytes = good;
    bytes[0] = 'X';
    expect_rejected(bytes, "expected 'LASF'");
    expect_rejected({'p', 'l', 'y', '\n', 'f'}, "expected 'LASF'");
}

TEST_F(LasBadInput, ShorterThanHeader) { expect_rejected(Bytes(good.begin(), good.begin() + 100), "227"); }

TEST_F(LasBadInput, TruncatedPointData) {
    write_las(cloud_of_format(1, 100), dir / "big.las");
    Bytes bytes = load_file(dir / "big.las");
    bytes.resize(bytes.size() - 5);
    expect_rejected(bytes, "truncated");
}

TEST_F(LasBadInput, HugePointCounts) {
    Bytes bytes = good;
    poke<std::uint64_t>(bytes, 247, std::uint64_t{1} << 60);  // 1.4 count
    expect_rejected(bytes, "points of");
    PointCloud cloud = cloud_of_format(0, 3);
    write_las(cloud, dir / "legacy.las");
    bytes = load_file(dir / "legacy.las");
    poke<std::uint32_t>(bytes, 107, 0xffffffffu);
    expect_rejected(bytes, "4294967295 points");
}

TEST_F(LasBadInput, HeaderFieldsOutOfRange) {
    Bytes bytes = good;
    poke<std::uint16_t>(bytes, 94, 100);
    expect_rejected(bytes, "header size 100");
    bytes = good;
    poke<std::uint32_t>(bytes, 96, 1u << 30);
    expect_rejected(bytes, "beyond the end of the file");
    bytes = good;
    bytes[25] = 9;
    expect_rejected(bytes, "version 1.9");
    bytes = good;
    bytes[104] = 11;
    expect_rejected(bytes, "point data format 11");
    bytes = good;
    bytes[104] = 0x81;  // marked LAZ but without the LASzip VLR that describes the compression
    expect_rejected(bytes, "no LASzip VLR");
    bytes = good;
    poke<std::uint16_t>(bytes, 105, 10);
    expect_rejected(bytes, "record length 10");
    bytes = good;
    poke<double>(bytes, 139, 0.0);
    expect_rejected(bytes, "y scale factor");
    bytes = good;
    poke<double>(bytes, 131, std::numeric_limits<double>::quiet_NaN());
    expect_rejected(bytes, "x scale factor");
}

TEST_F(LasBadInput, VlrsRunningPastTheirSpace) {
    Bytes bytes = good;
    poke<std::uint32_t>(bytes, 100, 1000000);
    expect_rejected(bytes, "VLRs");
    bytes = good;
    poke<std::uint16_t>(bytes, 375 + 20, 60000);  // first VLR's length
    expect_rejected(bytes, "past the start of point data");
    bytes = good;
    poke<std::uint32_t>(bytes, 243, 5000);  // EVLR count
    expect_rejected(bytes, "extended VLRs");
}

TEST_F(LasBadInput, ExtraBytesLongerThanTheRecord) {
    Bytes bytes = good;
    const std::size_t descriptor = descriptor_offset(bytes, 1);
    bytes[descriptor + 2] = 0;
    bytes[descriptor + 3] = 200;  // 200 undocumented bytes in a 38-byte record
    expect_rejected(bytes, "records are only");
}

TEST_F(LasBadInput, EveryTruncationIsAnError) {
    for (std::size_t size = 0; size < good.size(); ++size) {
        save_file(dir / "cut.las", Bytes(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(size)));
        EXPECT_EQ(error_code_of([&] { read_las(dir / "cut.las"); }), ExitCode::InvalidInput) << "size " << size;
    }
}

TEST_F(LasBadInput, RandomCorruptionGivesErrorsNotCrashes) {
    std::mt19937 rng(2024);
    const std::size_t region = std::min<std::size_t>(good.size(), 1400);  // header, VLRs, points, EVLR
    std::uniform_int_distribution<std::size_t> position(0, region - 1);
    std::uniform_int_distribution<int> byte(0, 255), flips(1, 4);
    int rejected = 0;
    const LogLevel level = log_level();
    set_log_level(LogLevel::Error);  // corrupt descriptors are warned about 2000 times otherwise
    for (int trial = 0; trial < 2000; ++trial) {
        Bytes bytes = good;
        for (int f = flips(rng); f > 0; --f) bytes[position(rng)] = static_cast<std::uint8_t>(byte(rng));
        save_file(dir / "fuzz.las", bytes);
        try {
            const PointCloud cloud = read_las(dir / "fuzz.las");
            for (const auto& p : cloud.positions) ASSERT_TRUE(p.allFinite()) << "trial " << trial;
            ASSERT_NO_THROW(cloud.check_consistent("fuzz"));
        } catch (const Error& e) {
            ASSERT_EQ(e.code(), ExitCode::InvalidInput) << e.what();
            ++rejected;
        }
    }
    set_log_level(level);
    EXPECT_GT(rejected, 0);
}
