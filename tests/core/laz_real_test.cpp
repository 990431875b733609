// LAZ and COPC on the real files of ../shared/data/laz (ctest label `real`): every LAZ decodes to
// exactly the point records of its uncompressed twin, byte for byte; the COPC file holds the
// same multiset of points as its LAS twin; selective decoding, COPC bounds queries, parallel
// decoding and damaged files (truncation, bit flips, a broken chunk table).
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/las_io.hpp"
#include "core/little_endian.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

using namespace treelobes;
using treelobes::test::real_data;
using treelobes::test::TempDir;

namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes file_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Index of the first record that differs, or -1.
long first_difference(const LasRecords& a, const LasRecords& b) {
    for (std::size_t i = 0; i < a.point_count; ++i)
        if (std::memcmp(a.points.data() + i * a.record_length, b.points.data() + i * b.record_length, a.record_length) != 0)
            return static_cast<long>(i);
    return -1;
}

void expect_twins(const std::string& laz, const std::string& las) {
    const LasRecords compressed = read_las_records(real_data(laz));
    const LasRecords plain = read_las_records(real_data(las));
    EXPECT_TRUE(compressed.compressed) << laz;
    EXPECT_FALSE(plain.compressed) << las;
    ASSERT_EQ(compressed.point_format, plain.point_format) << laz;
    ASSERT_EQ(compressed.record_length, plain.record_length) << laz;
    ASSERT_EQ(compressed.point_count, plain.point_count) << laz;
    EXPECT_EQ(first_difference(compressed, plain), -1) << laz << " differs from " << las;
}

}  // namespace

TEST(LazReal, PointFormats0To3DecodeToTheirTwins) {
    expect_twins("laz/MixedConifer.laz", "lidr/MixedConifer.las");    // format 1, treeID extra bytes
    expect_twins("laz/pine.laz", "treels/pine.las");                  // format 0
    expect_twins("laz/pine_plot.laz", "treels/pine_plot.las");        // format 0, several chunks
    expect_twins("laz/laspy/simple.laz", "laz/laspy/simple.las");     // format 3
    expect_twins("laz/laspy/extra.laz", "laz/laspy/extrabytes.las");  // LAS 1.4 format 3 + extra bytes
}

TEST(LazReal, LayeredFormat6DecodesToItsTwin) { expect_twins("laz/laspy/1_4_w_evlr.laz", "laz/laspy/1_4_w_evlr.las"); }

namespace {

// The fields formats 3 and 7 share, in a comparable form: coordinates in millimetres (the COPC
// file has its own offsets), format 7's scan angle (0.006 degree steps) in whole degrees like
// format 3's rank.
struct PointKey {
    std::int64_t x, y, z;
    int intensity, return_number, returns, classification, flags, direction_and_edge, scan_angle, user_data, source;
    std::uint64_t gps_time;
    int red, green, blue;
    auto operator<=>(const PointKey&) const = default;
};

PointKey key_of(const std::uint8_t* r, int format, const Bytes& header) {
    const bool extended = format >= 6;
    const std::size_t gps = extended ? 22 : 20, rgb = extended ? 30 : 28;
    auto millimetres = [&](int k) {
        const double value =
                load<std::int32_t>(r + 4 * k) * load<double>(header.data() + 131 + 8 * k) + load<double>(header.data() + 155 + 8 * k);
        return std::llround(value * 1000);
    };
    return {millimetres(0),
            millimetres(1),
            millimetres(2),
            load<std::uint16_t>(r + 12),
            extended ? r[14] & 0x0F : r[14] & 0x07,
            extended ? r[14] >> 4 : (r[14] >> 3) & 0x07,
            extended ? r[16] : r[15] & 0x1F,
            extended ? r[15] & 0x07 : r[15] >> 5,  // synthetic, key-point, withheld
            extended ? r[15] >> 6 : r[14] >> 6,    // scan direction, edge of flight line
            extended ? static_cast<int>(std::lround(load<std::int16_t>(r + 18) * 0.006)) : static_cast<std::int8_t>(r[16]),
            r[17],
            load<std::uint16_t>(r + (extended ? 20 : 18)),
            load<std::uint64_t>(r + gps),
            load<std::uint16_t>(r + rgb),
            load<std::uint16_t>(r + rgb + 2),
            load<std::uint16_t>(r + rgb + 4)};
}

std::vector<PointKey> sorted_keys(const LasRecords& records) {
    std::vector<PointKey> keys;
    for (std::size_t i = 0; i < records.point_count; ++i)
        keys.push_back(key_of(records.points.data() + i * records.record_length, records.point_format, records.header));
    std::sort(keys.begin(), keys.end());
    return keys;
}

}  // namespace

TEST(LazReal, CopcHoldsTheSamePointsAsItsTwin) {
    const LasRecords copc = read_las_records(real_data("laz/laspy/simple.copc.laz"));
    const LasRecords plain = read_las_records(real_data("laz/laspy/simple.las"));
    EXPECT_EQ(copc.point_format, 7);
    ASSERT_EQ(copc.point_count, plain.point_count);
    EXPECT_EQ(sorted_keys(copc), sorted_keys(plain));
}

TEST(LazReal, PointCloudsFromLazEqualThoseFromTheirTwins) {
    const PointCloud laz = read_point_cloud(real_data("laz/MixedConifer.laz"));
    const PointCloud las = read_point_cloud(real_data("lidr/MixedConifer.las"));
    ASSERT_EQ(laz.size(), las.size());
    EXPECT_EQ(laz.origin, las.origin);
    EXPECT_EQ(laz.positions, las.positions);
    EXPECT_EQ(laz.gps_time, las.gps_time);
    ASSERT_NE(laz.extra("treeID"), nullptr);
    EXPECT_EQ(laz.extra("treeID")->values, las.extra("treeID")->values);
    EXPECT_EQ(laz.georef.las_vlrs.size(), las.georef.las_vlrs.size());
    EXPECT_TRUE(laz.source.laz);
    EXPECT_EQ(laz.source.laz_chunk_size, 50000u);
    EXPECT_EQ(laz.source.las_scale, las.source.las_scale);
}

TEST(LazReal, FilesWithoutTwinsMatchTheirHeaders) {
    for (const char* name : {"laz/laspy/autzen_trim.laz", "laz/laspy/plane.laz"}) {
        const LasRecords records = read_las_records(real_data(name));
        const PointCloud cloud = read_point_cloud(real_data(name));
        EXPECT_EQ(cloud.size(), records.point_count) << name;
        // Header min/max (x, y, z) against the decoded points, to the coordinate scale.
        const auto [lo, hi] = cloud.bounds();
        for (int k = 0; k < 3; ++k) {
            const double max = load<double>(records.header.data() + 179 + 16 * k);
            const double min = load<double>(records.header.data() + 187 + 16 * k);
            const double scale = load<double>(records.header.data() + 131 + 8 * k);
            EXPECT_NEAR(cloud.origin[k] + lo[k], min, scale + 1e-3) << name << " axis " << k;
            EXPECT_NEAR(cloud.origin[k] + hi[k], max, scale + 1e-3) << name << " axis " << k;
        }
        // Return numbers within their counts, as in any sane scan.
        for (std::size_t i = 0; i < cloud.size(); ++i)
            ASSERT_LE(cloud.return_number[i], cloud.number_of_returns[i]) << name << " point " << i;
    }
    EXPECT_EQ(read_las_records(real_data("laz/laspy/autzen_trim.laz")).point_count, 110000u);
}

TEST(LazReal, SelectiveDecodingKeepsPositionsAndClassification) {
    for (const char* name : {"laz/laspy/simple.copc.laz", "laz/laspy/1_4_w_evlr.laz", "laz/MixedConifer.laz"}) {
        const PointCloud full = read_point_cloud(real_data(name));
        CloudReadOptions options;
        options.xyz_classification_only = true;
        const PointCloud lean = read_point_cloud(real_data(name), options);
        EXPECT_EQ(lean.positions, full.positions) << name;
        EXPECT_EQ(lean.classification, full.classification) << name;
        EXPECT_EQ(lean.return_number, full.return_number) << name;
        EXPECT_TRUE(lean.intensity.empty() && lean.gps_time.empty() && lean.rgb.empty()) << name;
        EXPECT_EQ(lean.extras.size(), full.extras.size()) << name;
    }
}

TEST(LazReal, CopcBoundsQueryReadsOnlyTheNodesItNeeds) {
    const auto file = real_data("laz/laspy/simple.copc.laz");
    const PointCloud full = read_point_cloud(file);
    EXPECT_GE(full.source.copc_levels, 1);
    EXPECT_GT(full.source.copc_nodes, 1u);
    EXPECT_EQ(full.source.copc_nodes_read, full.source.copc_nodes);
    // The south-west quarter of the cloud in x and y (2-D box).
    const auto [lo, hi] = full.bounds();
    const Eigen::Vector3d min = full.origin + lo.cast<double>(), max = full.origin + hi.cast<double>();
    Box3d box{{min.x(), min.y(), -1e300}, {(min.x() + max.x()) / 2, (min.y() + max.y()) / 2, 1e300}};
    CloudReadOptions options;
    options.bounds = box;
    const PointCloud part = read_point_cloud(file, options);
    EXPECT_LT(part.source.copc_nodes_read, part.source.copc_nodes);
    // Expected count from the exact coordinates (integer records times scale plus offset).
    const LasRecords records = read_las_records(file);
    std::size_t expected = 0;
    for (std::size_t i = 0; i < records.point_count; ++i) {
        Eigen::Vector3d p;
        for (int k = 0; k < 3; ++k)
            p[k] = load<std::int32_t>(records.points.data() + i * records.record_length + 4 * k) *
                           load<double>(records.header.data() + 131 + 8 * k) +
                   load<double>(records.header.data() + 155 + 8 * k);
        expected += box.contains(p) ? 1 : 0;
    }
    EXPECT_GT(expected, 0u);
    EXPECT_EQ(part.size(), expected);
    // A box away from every point reads nothing.
    options.bounds = Box3d{{max.x() + 10, max.y() + 10, -1e300}, {max.x() + 20, max.y() + 20, 1e300}};
    const PointCloud none = read_point_cloud(file, options);
    EXPECT_EQ(none.size(), 0u);
    EXPECT_EQ(none.source.copc_nodes_read, 0u);
}

TEST(LazReal, OneThreadAndManyThreadsDecodeTheSame) {
    const auto file = real_data("laz/pine_plot.laz");
    const LasRecords parallel = read_las_records(file);
    const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const LasRecords serial = read_las_records(file);
    EXPECT_EQ(parallel.points, serial.points);
}

// ---------------------------------------------------------------------------------------------
// Damaged files: one Error(InvalidInput) or a successful decode, never a crash or a hang.

namespace {

bool fails_cleanly_or_reads(const Bytes& bytes) {
    try {
        read_las_buffer(bytes, "damaged.laz");
        return true;
    } catch (const Error& e) {
        return e.code() == ExitCode::InvalidInput && std::string(e.what()).find('\n') == std::string::npos;
    }
}

}  // namespace

TEST(LazReal, TruncatedFilesFailWithOneLine) {
    for (const char* name : {"laz/laspy/simple.laz", "laz/laspy/simple.copc.laz", "laz/laspy/1_4_w_evlr.laz"}) {
        const Bytes whole = file_bytes(real_data(name));
        for (double fraction : {0.1, 0.5, 0.9, 0.99}) {
            const Bytes cut(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(whole.size() * fraction));
            try {
                read_las_buffer(cut, "cut.laz");
                ADD_FAILURE() << name << " cut to " << fraction << " was read without error";
            } catch (const Error& e) {
                EXPECT_EQ(e.code(), ExitCode::InvalidInput);
                EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
            }
        }
    }
}

TEST(LazReal, BitFlipsInTheCompressedStreamNeverCrash) {
    for (const char* name : {"laz/laspy/simple.laz", "laz/laspy/1_4_w_evlr.laz", "laz/laspy/simple.copc.laz"}) {
        const Bytes whole = file_bytes(real_data(name));
        const std::size_t points_start = load<std::uint32_t>(whole.data() + 96);
        std::mt19937 rng(11);
        for (int trial = 0; trial < 60; ++trial) {
            Bytes damaged = whole;
            for (int flips = 0; flips < 4; ++flips) {
                const std::size_t at = points_start + rng() % (whole.size() - points_start);
                damaged[at] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
            }
            EXPECT_TRUE(fails_cleanly_or_reads(damaged)) << name << " trial " << trial;
        }
    }
}

TEST(LazReal, ChunkTableOffsetPastTheEndIsAnError) {
    Bytes bytes = file_bytes(real_data("laz/laspy/simple.laz"));
    const std::size_t points_start = load<std::uint32_t>(bytes.data() + 96);
    store<std::uint64_t>(bytes.data() + points_start, bytes.size() + 100);
    try {
        read_las_buffer(bytes, "moved.laz");
        ADD_FAILURE() << "a chunk table past the end was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("chunk table offset"), std::string::npos) << e.what();
    }
}
