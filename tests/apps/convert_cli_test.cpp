// `treelobes convert` without real data: text and PLY round trips through LAS, usage errors
// (LAZ output, a bad --bounds) and unreadable input.
#include "core/cloud_io.hpp"
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
