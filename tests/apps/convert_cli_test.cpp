// `treelobes convert` without real data: text and PLY round trips through LAS, usage errors
// (LAZ output, a bad --bounds), unreadable input, and a survey in feet given in metres.
#include "core/cloud_io.hpp"
#include "core/crs_units.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>

using namespace treelobes;
using treelobes::test::run_cli;
using treelobes::test::TempDir;
using treelobes::test::write_text;

TEST(ConvertCli, TextToLasToPlyKeepsThePoints) {
    TempDir dir;
    write_text(dir / "a.xyz", "1000.5 2000.25 30\n1001 2001 31\n1002 2002 32.5\n");
    const auto las = run_cli("--json convert '" + (dir / "a.xyz").string() + "' --out '" + (dir / "a.las").string() + "'");
    ASSERT_EQ(las.exit_code, 0) << las.err;
    EXPECT_EQ(nlohmann::json::parse(las.out)["points"], 3);
    EXPECT_EQ(nlohmann::json::parse(las.out)["method"], "cloud");
    const auto ply = run_cli("convert '" + (dir / "a.las").string() + "' --out '" + (dir / "a.ply").string() + "'");
    ASSERT_EQ(ply.exit_code, 0) << ply.err;
    const PointCloud back = read_point_cloud(dir / "a.ply");
    ASSERT_EQ(back.size(), 3u);
    EXPECT_NEAR(back.global(2).z(), 32.5, 1e-3);
    EXPECT_NEAR(back.global(0).x(), 1000.5, 1e-3);
}

TEST(ConvertCli, LasToLasCopiesTheRecords) {
    TempDir dir;
    write_text(dir / "a.xyz", "1 2 3\n4 5 6\n");
    ASSERT_EQ(run_cli("convert '" + (dir / "a.xyz").string() + "' --out '" + (dir / "a.las").string() + "'").exit_code, 0);
    const auto copy = run_cli("--json convert '" + (dir / "a.las").string() + "' --out '" + (dir / "b.las").string() + "'");
    ASSERT_EQ(copy.exit_code, 0) << copy.err;
    EXPECT_EQ(nlohmann::json::parse(copy.out)["method"], "records");
    EXPECT_EQ(read_point_cloud(dir / "b.las").positions, read_point_cloud(dir / "a.las").positions);
}

TEST(ConvertCli, BoundsKeepOnlyThePointsInside) {
    TempDir dir;
    write_text(dir / "a.xyz", "0 0 0\n5 5 5\n10 10 10\n");
    const auto r = run_cli("--json convert '" + (dir / "a.xyz").string() + "' --out '" + (dir / "b.xyz").string() + "' --bounds 1,1,9,9");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["points"], 1);
}

TEST(ConvertCli, ErrorsAreOneLine) {
    TempDir dir;
    write_text(dir / "a.xyz", "1 2 3\n");
    const std::string in = "'" + (dir / "a.xyz").string() + "'";
    EXPECT_EQ(run_cli("convert " + in + " --out '" + (dir / "b.laz").string() + "'").exit_code, 1);
    EXPECT_EQ(run_cli("convert " + in + " --out '" + (dir / "b.las").string() + "' --bounds 1,2,3").exit_code, 1);
    EXPECT_EQ(run_cli("convert " + in + " --out '" + (dir / "b.las").string() + "' --bounds 5,5,1,1").exit_code, 1);
    EXPECT_EQ(run_cli("convert " + in + " --out " + in).exit_code, 1);
    const auto missing = run_cli("convert '" + (dir / "missing.laz").string() + "' --out '" + (dir / "b.las").string() + "'");
    EXPECT_EQ(missing.exit_code, 2);
    EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "b.las"));
}

// --to-metres: a LAS in Oregon Lambert feet (laspy's autzen_trim.laz CRS) becomes the same projection in metres,
// x, y and z multiplied by 0.3048 (z in the unit of x and y: the CRS is 2D); a cloud without a
// CRS or in degrees is refused in one line and nothing is written.
TEST(ConvertCli, ToMetresMultipliesTheCoordinatesAndRewritesTheCrs) {
    TempDir dir;
    PointCloud feet;
    feet.origin = {1312000.0, 400000.0, 300.0};
    feet.positions = {{0.0f, 0.0f, 0.0f}, {100.0f, 50.0f, 65.6f}};
    feet.georef.crs_wkt =
            R"wkt(PROJCS["NAD_1983_HARN_Lambert_Conformal_Conic",GEOGCS["GCS_North_American_1983_HARN",DATUM["NAD83_HARN",)wkt"
            R"wkt(SPHEROID["GRS_1980",6378137,298.257222101]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],)wkt"
            R"wkt(PROJECTION["Lambert_Conformal_Conic_2SP"],PARAMETER["standard_parallel_1",43],PARAMETER["standard_parallel_2",45.5],)wkt"
            R"wkt(PARAMETER["latitude_of_origin",41.75],PARAMETER["central_meridian",-120.5],PARAMETER["false_easting",1312335.958],)wkt"
            R"wkt(PARAMETER["false_northing",0],UNIT["foot",0.3048]])wkt";
    write_point_cloud(feet, dir / "feet.las");
    const auto r =
            run_cli("--json convert '" + (dir / "feet.las").string() + "' --out '" + (dir / "metres.las").string() + "' --to-metres");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("x and y in foot multiplied by 0.3048, z in foot (assumed as horizontal) by 0.3048"), std::string::npos) << r.err;
    const PointCloud metres = read_point_cloud(dir / "metres.las");
    ASSERT_EQ(metres.size(), 2u);
    EXPECT_NEAR(metres.global(1).x(), 1312100.0 * 0.3048, 1e-3);
    EXPECT_NEAR(metres.global(1).z(), 365.6 * 0.3048, 1e-3);
    EXPECT_TRUE(crs_horizontal_unit(metres.georef.crs_wkt)->is_metre()) << metres.georef.crs_wkt;
    EXPECT_EQ(metres.source.version, "1.4");  // a WKT CRS, with the global encoding's WKT bit

    for (const std::string& crs :
         {std::string(),
          std::string(
                  R"wkt(GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],UNIT["degree",0.0174532925199433]])wkt")}) {
        PointCloud other = feet;
        other.georef.crs_wkt = crs;
        write_point_cloud(other, dir / "other.las");
        const auto refused =
                run_cli("convert '" + (dir / "other.las").string() + "' --out '" + (dir / "out.las").string() + "' --to-metres");
        EXPECT_EQ(refused.exit_code, 2) << crs;
        EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
        EXPECT_FALSE(std::filesystem::exists(dir / "out.las"));
    }
}
