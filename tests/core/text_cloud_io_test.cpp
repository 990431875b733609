#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

using namespace treelobes;
using treelobes::test::TempDir;
using treelobes::test::write_text;

namespace {

ExitCode read_error_code(const std::filesystem::path& path, std::string* message = nullptr) {
    try {
        read_point_cloud(path);
    } catch (const Error& e) {
        if (message) *message = e.what();
        return e.code();
    }
    return ExitCode::Ok;
}

}  // namespace

TEST(TextCloud, ReadsSpaceSeparatedWithTrailingBlanksAndNoFinalNewline) {
    TempDir dir;
    write_text(dir / "a.xyz", "0.132 18.645 3.971 \r\n1 2 3 \r\n-4.5 5e-1 6");
    const PointCloud cloud = read_point_cloud(dir / "a.xyz");
    ASSERT_EQ(cloud.size(), 3u);
    EXPECT_NEAR(cloud.global(0).x(), 0.132, 1e-6);
    EXPECT_NEAR(cloud.global(2).y(), 0.5, 1e-6);
    EXPECT_NEAR(cloud.global(2).z(), 6.0, 1e-6);
    EXPECT_TRUE(cloud.extras.empty());
}

TEST(TextCloud, ReadsCommaAndTabSeparatedFilesWithHeader) {
    TempDir dir;
    write_text(dir / "a.csv", "X,Y,Z,Intensity,tree\n1,2,3,100,7\n4,5,6,200,8\n");
    const PointCloud csv = read_point_cloud(dir / "a.csv");
    ASSERT_EQ(csv.size(), 2u);
    ASSERT_EQ(csv.intensity.size(), 2u);
    EXPECT_EQ(csv.intensity[1], 200);
    ASSERT_NE(csv.extra("tree"), nullptr);
    EXPECT_DOUBLE_EQ(csv.extra("tree")->values[0], 7.0);

    write_text(dir / "b.txt", "//X\tY\tZ\n1\t2\t3\n");
    EXPECT_EQ(read_point_cloud(dir / "b.txt").size(), 1u);
}

TEST(TextCloud, ExtraColumnsWithoutHeaderBecomeNumberedAttributes) {
    TempDir dir;
    write_text(dir / "a.xyz", "1 2 3 9 8\n4 5 6 7 6\n");
    const PointCloud cloud = read_point_cloud(dir / "a.xyz");
    ASSERT_NE(cloud.extra("column_4"), nullptr);
    EXPECT_DOUBLE_EQ(cloud.extra("column_5")->values[1], 6.0);
}

TEST(TextCloud, DropsNonFiniteCoordinatesAndCountsThem) {
    TempDir dir;
    write_text(dir / "a.xyz", "1 2 3\nnan 2 3\n1 inf 3\n4 5 6\n");
    const PointCloud cloud = read_point_cloud(dir / "a.xyz");
    EXPECT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.source.dropped_non_finite, 2u);

    write_text(dir / "b.xyz", "nan nan nan\n");
    EXPECT_EQ(read_error_code(dir / "b.xyz"), ExitCode::InvalidInput);
}

TEST(TextCloud, RejectsBadInputWithLineNumbers) {
    TempDir dir;
    std::string message;
    write_text(dir / "a.xyz", "1 2 3\n4 five 6\n");
    EXPECT_EQ(read_error_code(dir / "a.xyz", &message), ExitCode::InvalidInput);
    EXPECT_NE(message.find("line 2"), std::string::npos) << message;

    write_text(dir / "short.xyz", "1 2\n");
    EXPECT_EQ(read_error_code(dir / "short.xyz"), ExitCode::InvalidInput);
    write_text(dir / "empty.xyz", "");
    EXPECT_EQ(read_error_code(dir / "empty.xyz"), ExitCode::InvalidInput);
    write_text(dir / "binary.xyz", std::string("\x01\x00\xff\xfe garbage", 12));
    EXPECT_EQ(read_error_code(dir / "binary.xyz"), ExitCode::InvalidInput);
    EXPECT_EQ(read_error_code(dir.path()), ExitCode::InvalidInput);
    EXPECT_EQ(read_error_code(dir / "missing.xyz"), ExitCode::InvalidInput);
}

TEST(TextCloud, UtmCoordinatesSurviveWriteAndReadBelowOneMillimetre) {
    TempDir dir;
    write_text(dir / "utm.xyz", "650000.1234 5800000.5678 101.25\n650010.0001 5800020.9999 99.5\n");
    const PointCloud cloud = read_point_cloud(dir / "utm.xyz");
    EXPECT_GT(cloud.origin.x(), 6e5 - 1e3);
    write_point_cloud(cloud, dir / "copy.xyz");
    const PointCloud back = read_point_cloud(dir / "copy.xyz");
    ASSERT_EQ(back.size(), 2u);
    EXPECT_NEAR(back.global(0).x(), 650000.1234, 1e-3);
    EXPECT_NEAR(back.global(0).y(), 5800000.5678, 1e-3);
    EXPECT_NEAR(back.global(1).y(), 5800020.9999, 1e-3);
}

TEST(TextCloud, WritesAttributesAsHeaderedColumns) {
    TempDir dir;
    PointCloud cloud;
    cloud.positions = {{1, 2, 3}, {4, 5, 6}};
    cloud.intensity = {10, 20};
    cloud.add_extra("treeID", AttributeType::Int32, 3);
    write_point_cloud(cloud, dir / "out.csv");
    const PointCloud back = read_point_cloud(dir / "out.csv");
    ASSERT_EQ(back.intensity.size(), 2u);
    EXPECT_EQ(back.intensity[1], 20);
    ASSERT_NE(back.extra("treeID"), nullptr);
    EXPECT_DOUBLE_EQ(back.extra("treeID")->values[1], 3.0);
}

TEST(CloudIo, DamagedLazAndUnknownFormatsAreRejectedClearly) {
    TempDir dir;
    write_text(dir / "a.laz", "LASF");  // .laz goes to the LAS/LAZ reader, which finds no header
    std::string message;
    EXPECT_EQ(read_error_code(dir / "a.laz", &message), ExitCode::InvalidInput);
    EXPECT_NE(message.find("shorter than the 227-byte LAS header"), std::string::npos) << message;
    write_text(dir / "a.foo", "hello");
    EXPECT_EQ(read_error_code(dir / "a.foo"), ExitCode::InvalidInput);
}

// Fuzzing found it (UBSan: nan outside the range of unsigned short): a NaN attribute value is
// "no value" and becomes 0; out-of-range values clamp.
TEST(TextCloud, NanAndOutOfRangeAttributesBecomeValidIntegers) {
    TempDir dir;
    write_text(dir / "a.xyz",
               "x y z intensity classification red green blue\n"
               "1 2 3 nan nan nan nan nan\n"
               "4 5 6 70000 -3 1e300 -1e300 12\n");
    const PointCloud cloud = read_text_cloud(dir / "a.xyz");
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.intensity, (std::vector<std::uint16_t>{0, 65535}));
    EXPECT_EQ(cloud.classification, (std::vector<std::uint8_t>{0, 0}));
    ASSERT_EQ(cloud.rgb.size(), 2u);
    EXPECT_EQ(cloud.rgb[0], (std::array<std::uint16_t, 3>{0, 0, 0}));
    EXPECT_EQ(cloud.rgb[1], (std::array<std::uint16_t, 3>{65535, 0, 12}));
}
