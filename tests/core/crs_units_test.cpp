// The units of a CRS read from its WKT: WKT 1 and 2, projected in metres or feet, compound (and
// its vertical part), geographic, and texts that name none; units by the EPSG codes of GeoTIFF
// keys (a cloud's units, which fall back to PROJ: crs_metres_test.cpp).
#include "core/crs_units.hpp"

#include <gtest/gtest.h>

using namespace treelobes;

TEST(CrsUnits, Wkt1ProjectedInFeetIsNotTakenForItsGeographicDegrees) {
    // The shape of laspy's autzen_trim.laz CRS: the GEOGCS inside has its own (angular) unit.
    const auto unit = crs_horizontal_unit(
            R"wkt(PROJCS["NAD_1983_HARN_Lambert_Conformal_Conic",GEOGCS["GCS_North_American_1983_HARN",DATUM["NAD83_High_Accuracy_Regional_Network",)wkt"
            R"wkt(SPHEROID["GRS_1980",6378137,298.257222101]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],)wkt"
            R"wkt(PROJECTION["Lambert_Conformal_Conic_2SP"],PARAMETER["false_easting",1312335.958],UNIT["foot",0.3048,AUTHORITY["EPSG","9002"]]])wkt");
    ASSERT_TRUE(unit);
    EXPECT_EQ(unit->name, "foot");
    EXPECT_DOUBLE_EQ(unit->metres, 0.3048);
    EXPECT_FALSE(unit->is_metre());
}

TEST(CrsUnits, Wkt1InMetresAndACompoundCrsByItsHorizontalPart) {
    const auto utm = crs_horizontal_unit(
            R"wkt(PROJCS["NAD83 / UTM zone 17N",GEOGCS["NAD83",UNIT["degree",0.0174532925199433]],UNIT["metre",1]])wkt");
    ASSERT_TRUE(utm);
    EXPECT_TRUE(utm->is_metre());
    const auto compound = crs_horizontal_unit(
            R"wkt(COMPD_CS["x",PROJCS["y",GEOGCS["g",UNIT["degree",0.0174532925199433]],UNIT["US survey foot",0.304800609601219]],)wkt"
            R"wkt(VERT_CS["NAVD88",UNIT["metre",1]]])wkt");
    ASSERT_TRUE(compound);
    EXPECT_EQ(compound->name, "US survey foot");
    EXPECT_NEAR(compound->metres, 0.3048006, 1e-7);
}

TEST(CrsUnits, Wkt2TakesTheCoordinateSystemsUnitNotTheConversionsParameters) {
    const auto unit = crs_horizontal_unit(
            R"wkt(PROJCRS["NAD83(HARN) / Oregon GIC Lambert (ft)",BASEGEOGCRS["NAD83(HARN)",ANGLEUNIT["degree",0.0174532925199433]],)wkt"
            R"wkt(CONVERSION["x",PARAMETER["False easting",400000,LENGTHUNIT["metre",1]]],CS[Cartesian,2],)wkt"
            R"wkt(AXIS["easting (X)",east,LENGTHUNIT["foot",0.3048]],AXIS["northing (Y)",north,LENGTHUNIT["foot",0.3048]]])wkt");
    ASSERT_TRUE(unit);
    EXPECT_EQ(unit->name, "foot");
}

TEST(CrsUnits, GeographicIsAngularAndOtherTextsNameNone) {
    const auto geographic = crs_horizontal_unit(R"wkt(GEOGCS["WGS 84",DATUM["WGS_1984"],UNIT["degree",0.0174532925199433]])wkt");
    ASSERT_TRUE(geographic);
    EXPECT_TRUE(geographic->angular);
    EXPECT_FALSE(geographic->is_metre());
    for (const char* none : {"", "EPSG:26917", "PROJCS[\"broken\",UNIT[", "PROJCS[\"no unit\"]"})
        EXPECT_FALSE(crs_horizontal_unit(none)) << none;
}

TEST(CrsUnits, TheVerticalPartOfACompoundCrsHasItsOwnUnit) {
    // laspy's simple.copc.laz: metres across, US survey feet up (WKT 1 and WKT 2 spellings).
    const auto wkt1 = crs_vertical_unit(
            R"wkt(COMPD_CS["NAD83 / Oregon LCC (m) + NAVD88 height (ftUS)",PROJCS["NAD83 / Oregon LCC (m)",GEOGCS["NAD83",)wkt"
            R"wkt(UNIT["degree",0.0174532925199433]],UNIT["metre",1]],VERT_CS["NAVD88 height (ftUS)",VERT_DATUM["x",2005],)wkt"
            R"wkt(UNIT["US survey foot",0.304800609601219],AXIS["Gravity-related height",UP]]])wkt");
    ASSERT_TRUE(wkt1);
    EXPECT_EQ(wkt1->name, "US survey foot");
    const auto wkt2 = crs_vertical_unit(
            R"wkt(COMPOUNDCRS["x",PROJCRS["y",CS[Cartesian,2],AXIS["easting",east,LENGTHUNIT["metre",1]]],VERTCRS["NAVD88 height (ftUS)",)wkt"
            R"wkt(VDATUM["NAVD88"],CS[vertical,1],AXIS["gravity-related height (H)",up,LENGTHUNIT["US survey foot",0.304800609601219]]]])wkt");
    ASSERT_TRUE(wkt2);
    EXPECT_NEAR(wkt2->metres, 0.3048006, 1e-7);
    const auto metre = crs_vertical_unit(R"wkt(COMPD_CS["x",PROJCS["y",UNIT["metre",1]],VERT_CS["DHHN2016 height",UNIT["metre",1]]])wkt");
    ASSERT_TRUE(metre);
    EXPECT_TRUE(metre->is_metre());
    for (const char* none :
         {"", "EPSG:26917", R"wkt(PROJCS["y",UNIT["foot",0.3048]])wkt", "VERT_CS[\"broken\",UNIT[", "VERTCRS[\"no cs\"]"})
        EXPECT_FALSE(crs_vertical_unit(none)) << none;
}
