// LAS reader/writer on the real scans in ../shared/data (ctest label `real`): counts, formats and
// attributes as published, and a write -> read round trip of lidR's MixedConifer.las.
#include "core/cloud_io.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace treelobes;
using treelobes::test::real_data;
using treelobes::test::TempDir;

namespace {

std::set<double> distinct_values(const ExtraAttribute& attribute) {
    std::set<double> values;
    for (double v : attribute.values)
        if (!attribute.no_data || v != *attribute.no_data) values.insert(v);
    return values;
}

// Float local coordinates must stay small for sub-millimetre precision.
void expect_small_local_coordinates(const PointCloud& cloud) {
    const auto [lo, hi] = cloud.bounds();
    EXPECT_LT(lo.cwiseAbs().maxCoeff(), 4096.0f);
    EXPECT_LT(hi.cwiseAbs().maxCoeff(), 4096.0f);
}

}  // namespace

TEST(LasReal, MixedConiferHasTreeIds) {
    const PointCloud cloud = read_las(real_data("lidr/MixedConifer.las"));
    EXPECT_EQ(cloud.size(), 37657u);
    EXPECT_EQ(cloud.source.version, "1.2");
    EXPECT_EQ(cloud.source.las_point_format, 1);
    EXPECT_EQ(cloud.gps_time.size(), cloud.size());
    EXPECT_TRUE(cloud.rgb.empty());
    const ExtraAttribute* tree = cloud.extra("treeID");
    ASSERT_NE(tree, nullptr);
    EXPECT_EQ(tree->type, AttributeType::Float64);
    ASSERT_TRUE(tree->no_data.has_value());
    EXPECT_GT(*tree->no_data, 1.79e308);
    EXPECT_EQ(distinct_values(*tree).size(), 205u);
    EXPECT_EQ(cloud.georef.crs_wkt, "EPSG:26912");  // NAD83 / UTM 12N from the GeoKeys
    EXPECT_EQ(cloud.georef.las_vlrs.size(), 1u);
    // The header offset is 0 while x ~ 481,300 m: the origin must move next to the data.
    expect_small_local_coordinates(cloud);
    EXPECT_NEAR(cloud.global(0).x(), 481300, 100);
}

TEST(LasReal, PineIsFormat0) {
    const PointCloud cloud = read_las(real_data("treels/pine.las"));
    EXPECT_EQ(cloud.size(), 73851u);
    EXPECT_EQ(cloud.source.las_point_format, 0);
    EXPECT_EQ(cloud.source.version, "1.2");
    EXPECT_TRUE(cloud.gps_time.empty());
    EXPECT_TRUE(cloud.rgb.empty());
    EXPECT_EQ(cloud.classification.size(), cloud.size());
}

TEST(LasReal, ArchiTreeIsFormat3WithColour) {
    const PointCloud cloud = read_las(real_data("archi/tree1_points.las"));
    EXPECT_EQ(cloud.size(), 20198u);
    EXPECT_EQ(cloud.source.las_point_format, 3);
    EXPECT_EQ(cloud.rgb.size(), cloud.size());
    EXPECT_EQ(cloud.gps_time.size(), cloud.size());
    EXPECT_DOUBLE_EQ(cloud.source.las_scale.x(), 1e-7);
    expect_small_local_coordinates(cloud);
}

TEST(LasReal, DbhIsLas14WithClusterExtra) {
    const PointCloud cloud = read_las(real_data("lidr/dbh.las"));
    EXPECT_EQ(cloud.size(), 1369u);
    EXPECT_EQ(cloud.source.version, "1.4");
    EXPECT_EQ(cloud.source.las_point_format, 1);
    const ExtraAttribute* cluster = cloud.extra("cluster");
    ASSERT_NE(cluster, nullptr);
    EXPECT_EQ(cluster->type, AttributeType::Int32);
    EXPECT_EQ(cluster->values.size(), cloud.size());
    const ExtraAttribute* hag = cloud.extra("hag");
    ASSERT_NE(hag, nullptr);
    EXPECT_EQ(hag->description, "height above ground");
    // The slice lies 1.29-1.54 m above ground.
    for (double h : hag->values) {
        EXPECT_GE(h, 1.2);
        EXPECT_LE(h, 1.6);
    }
}

TEST(LasReal, MegaplotHasGroundAndOtherClasses) {
    const PointCloud cloud = read_las(real_data("lidr/Megaplot.las"));
    EXPECT_EQ(cloud.size(), 81590u);
    const std::set<std::uint8_t> classes(cloud.classification.begin(), cloud.classification.end());
    EXPECT_TRUE(classes.count(1));
    EXPECT_TRUE(classes.count(2));
    EXPECT_EQ(cloud.georef.crs_wkt, "EPSG:26917");
    expect_small_local_coordinates(cloud);
}

TEST(LasReal, MixedConiferRoundTrip) {
    TempDir dir;
    const PointCloud cloud = read_las(real_data("lidr/MixedConifer.las"));
    write_las(cloud, dir / "copy.las");
    const PointCloud back = read_las(dir / "copy.las");
    ASSERT_EQ(back.size(), cloud.size());
    const double half_step = cloud.source.las_scale.maxCoeff() / 2;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        ASSERT_LE((cloud.global(i) - back.global(i)).cwiseAbs().maxCoeff(), half_step) << "point " << i;
    EXPECT_EQ(back.source.las_point_format, 1);
    EXPECT_EQ(back.source.version, "1.4");  // extra attributes are written as LAS 1.4
    EXPECT_EQ(back.classification, cloud.classification);
    EXPECT_EQ(back.gps_time, cloud.gps_time);
    EXPECT_EQ(back.intensity, cloud.intensity);
    const ExtraAttribute* tree = back.extra("treeID");
    ASSERT_NE(tree, nullptr);
    EXPECT_EQ(tree->values, cloud.extra("treeID")->values);
    EXPECT_EQ(tree->no_data, cloud.extra("treeID")->no_data);
    EXPECT_EQ(tree->description, cloud.extra("treeID")->description);
    ASSERT_EQ(back.georef.las_vlrs.size(), 1u);
    EXPECT_EQ(back.georef.las_vlrs[0].data, cloud.georef.las_vlrs[0].data);
}
