// A CRS in feet given in metres (core/crs_metres.hpp): projected in feet (WKT and an EPSG code),
// a compound CRS with heights in US survey feet, and what cannot be converted; a cloud's units by
// its WKT, its GeoTIFF keys' unit codes or PROJ's registry.
#include "core/crs_metres.hpp"

#include "core/crs_units.hpp"
#include "core/error.hpp"

#include <gtest/gtest.h>

namespace treelobes {
namespace {

// laspy's autzen_trim.laz CRS: Oregon Lambert in feet (ESRI WKT 1), false easting 1312335.958 ft.
const char* kOregonFeet =
        R"wkt(PROJCS["NAD_1983_HARN_Lambert_Conformal_Conic",GEOGCS["GCS_North_American_1983_HARN",DATUM["NAD83_High_Accuracy_Regional_Network",)wkt"
        R"wkt(SPHEROID["GRS_1980",6378137,298.257222101]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],)wkt"
        R"wkt(PROJECTION["Lambert_Conformal_Conic_2SP"],PARAMETER["standard_parallel_1",43],PARAMETER["standard_parallel_2",45.5],)wkt"
        R"wkt(PARAMETER["latitude_of_origin",41.75],PARAMETER["central_meridian",-120.5],PARAMETER["false_easting",1312335.958],)wkt"
        R"wkt(PARAMETER["false_northing",0],UNIT["foot",0.3048]])wkt";

Georeference georef_of(const std::string& crs) {
    Georeference georef;
    georef.crs_wkt = crs;
    return georef;
}

TEST(CrsMetres, AProjectedCrsInFeetIsTheSameProjectionInMetres) {
    const MetricCrs metric = crs_in_metres(georef_of(kOregonFeet), "autzen");
    EXPECT_DOUBLE_EQ(metric.horizontal, 0.3048);
    EXPECT_DOUBLE_EQ(metric.vertical, 0.3048);
    EXPECT_EQ(metric.vertical_source, "assumed as horizontal");
    const auto unit = crs_horizontal_unit(metric.wkt);
    ASSERT_TRUE(unit) << metric.wkt;
    EXPECT_TRUE(unit->is_metre()) << metric.wkt;
    EXPECT_NE(metric.wkt.find("\"false_easting\",399999.99"), std::string::npos) << metric.wkt;  // 1312335.958 ft
    EXPECT_NE(metric.wkt.find("(in metres)"), std::string::npos) << metric.wkt;
}

TEST(CrsMetres, AnEpsgCodeIsLookedUpInProjsRegistry) {
    const MetricCrs metric = crs_in_metres(georef_of("EPSG:2992"), "code");  // NAD83 / Oregon GIC Lambert (ft)
    EXPECT_DOUBLE_EQ(metric.horizontal, 0.3048);
    EXPECT_TRUE(crs_horizontal_unit(metric.wkt)->is_metre()) << metric.wkt;
    const MetricCrs metres = crs_in_metres(georef_of("EPSG:26912"), "utm");  // already metres: unchanged
    EXPECT_DOUBLE_EQ(metres.horizontal, 1.0);
    EXPECT_EQ(metres.wkt.find("(in metres)"), std::string::npos) << metres.wkt;
}

TEST(CrsMetres, HeightsInUsSurveyFeetTakeTheVerticalUnit) {
    // laspy's simple.copc.laz: Oregon Lambert in metres + NAVD88 height (ftUS).
    const MetricCrs metric = crs_in_metres(georef_of("EPSG:2994+6360"), "copc");
    EXPECT_DOUBLE_EQ(metric.horizontal, 0.3048);  // EPSG:2994 is Oregon Lambert (ft)
    EXPECT_NEAR(metric.vertical, 1200.0 / 3937.0, 1e-12);
    EXPECT_EQ(metric.vertical_source, "vertical CRS");
    const auto vertical = crs_vertical_unit(metric.wkt);
    ASSERT_TRUE(vertical) << metric.wkt;
    EXPECT_TRUE(vertical->is_metre());
}

TEST(CrsMetres, WhatCannotBeConvertedIsRefused) {
    for (const char* crs :
         {"", "EPSG:4326", "not a CRS",
          R"wkt(GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],UNIT["degree",0.0174532925199433]])wkt"}) {
        try {
            crs_in_metres(georef_of(crs), "tile.las");
            ADD_FAILURE() << crs;
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput) << crs;
            EXPECT_NE(std::string(e.what()).find("tile.las"), std::string::npos) << e.what();
        }
    }
}

TEST(CrsMetres, TheCloudIsMultipliedAndTakesTheNewCrs) {
    PointCloud cloud;
    cloud.origin = {636000.0, 849000.0, 400.0};
    cloud.positions = {{1.0f, 2.0f, 6.0f}, {1000.0f, -500.0f, 100.0f}};
    cloud.source.las_scale = {0.01, 0.01, 0.01};
    cloud.source.las_offset = {636000.0, 849000.0, 0.0};
    cloud.georef = georef_of(kOregonFeet);
    cloud.georef.las_vlrs.push_back({});
    const MetricCrs metric = crs_in_metres(cloud.georef, "autzen");
    convert_to_metres(cloud, metric);
    EXPECT_NEAR(cloud.global(0).x(), 636001.0 * 0.3048, 1e-4);  // float local coordinates: well under a millimetre
    EXPECT_NEAR(cloud.global(1).y(), 848500.0 * 0.3048, 1e-4);
    EXPECT_NEAR(cloud.global(0).z(), 406.0 * 0.3048, 1e-4);
    EXPECT_DOUBLE_EQ(cloud.source.las_scale.x(), 0.01 * 0.3048);  // the stored integers stay the same
    EXPECT_DOUBLE_EQ(cloud.source.las_offset.x(), 636000.0 * 0.3048);
    EXPECT_EQ(cloud.georef.crs_wkt, metric.wkt);
    EXPECT_TRUE(cloud.georef.las_vlrs.empty());  // the records in feet would contradict it
}

TEST(CrsMetres, GeoTiffKeyUnitCodesServeWhenTheCrsIsOnlyACode) {
    EXPECT_TRUE(epsg_linear_unit(9001)->is_metre());
    EXPECT_DOUBLE_EQ(epsg_linear_unit(9002)->metres, 0.3048);
    EXPECT_EQ(epsg_linear_unit(9003)->name, "US survey foot");
    EXPECT_FALSE(epsg_linear_unit(0));
    EXPECT_FALSE(epsg_linear_unit(9102));  // degree: an angular unit, not a length
    Georeference georef;
    georef.crs_wkt = "EPSG:2992";  // NAD83 / Oregon GIC Lambert (ft): the code names no unit, the keys do
    georef.linear_unit_code = 9002;
    georef.vertical_unit_code = 9003;
    CrsUnits units = crs_units_of(georef);
    ASSERT_TRUE(units.horizontal && units.vertical);
    EXPECT_EQ(units.horizontal->name, "foot");
    EXPECT_EQ(units.vertical->name, "US survey foot");
    georef.crs_wkt = R"wkt(PROJCS["y",UNIT["metre",1]])wkt";  // a WKT says it itself
    units = crs_units_of(georef);
    EXPECT_TRUE(units.horizontal->is_metre());
    EXPECT_EQ(units.vertical->name, "US survey foot");
    EXPECT_FALSE(crs_units_of(Georeference{}).horizontal);
}

TEST(CrsMetres, TheUnitsOfACrsKnownOnlyByItsCodeComeFromProjsRegistry) {
    const CrsUnits feet = crs_units_of(georef_of("EPSG:2992"));  // NAD83 / Oregon GIC Lambert (ft), 2D
    ASSERT_TRUE(feet.horizontal);
    EXPECT_DOUBLE_EQ(feet.horizontal->metres, 0.3048);
    EXPECT_FALSE(feet.vertical);  // a 2D CRS names no unit for heights
    const CrsUnits compound = crs_units_of(georef_of("EPSG:2994+6360"));
    ASSERT_TRUE(compound.vertical);
    EXPECT_NEAR(compound.vertical->metres, 1200.0 / 3937.0, 1e-12);
    const CrsUnits geographic = crs_units_of(georef_of("EPSG:4326"));
    ASSERT_TRUE(geographic.horizontal);
    EXPECT_TRUE(geographic.horizontal->angular);
    for (const char* none : {"EPSG:0", "not a CRS"}) {
        const CrsUnits units = crs_units_of(georef_of(none));
        EXPECT_FALSE(units.horizontal || units.vertical) << none;
    }
}

}  // namespace
}  // namespace treelobes
