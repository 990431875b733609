// End-to-end tests of the CLI plumbing and `treelobes info` (exit codes, one-line errors, JSON).
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <iterator>

using treelobes::test::quoted;
using treelobes::test::run_cli;
using treelobes::test::TempDir;
using treelobes::test::write_text;

namespace {
int line_count(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }
}  // namespace

TEST(Cli, VersionAndHelp) {
    const auto version = run_cli("--version");
    EXPECT_EQ(version.exit_code, 0);
    EXPECT_NE(version.out.find("treelobes"), std::string::npos);
    const auto help = run_cli("--help");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.out.find("info"), std::string::npos);
    EXPECT_EQ(run_cli("info --help").exit_code, 0);
}

TEST(Cli, UsageErrorsExitWithOne) {
    EXPECT_EQ(run_cli("").exit_code, 1);
    EXPECT_EQ(run_cli("no-such-command").exit_code, 1);
    EXPECT_EQ(run_cli("info").exit_code, 1);
    EXPECT_EQ(run_cli("--log-level loud info x.xyz").exit_code, 1);
}

TEST(Cli, NumericOptionsMustBeFiniteAndInRange) {
    // One line naming the option, for nan and inf as for out-of-range values and non-numbers.
    for (const char* args : {"--threads nan info x.xyz", "--threads -1 info x.xyz", "reconstruct x.xyz --out o --outlier-ratio nan",
                             "reconstruct x.xyz --out o --outlier-sigma inf", "reconstruct x.xyz --out o --beta abc",
                             "reconstruct x.xyz --out o --internode-length -1"}) {
        const auto r = run_cli(args);
        EXPECT_EQ(r.exit_code, 1) << args;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 2) << args << ": " << r.err;  // the error and "Run with --help"
        EXPECT_TRUE(r.err.find("finite number") != std::string::npos || r.err.find("not a number") != std::string::npos) << r.err;
    }
}

TEST(Cli, InfoDescribesACloudAsJson) {
    TempDir dir;
    write_text(dir / "a.xyz", "1 2 3\n4 5 6\n-1 0 9\n");
    const auto result = run_cli("info --json '" + (dir / "a.xyz").string() + "'");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const auto json = nlohmann::json::parse(result.out);
    const auto& file = json["files"][0];
    EXPECT_EQ(file["points"], 3);
    EXPECT_EQ(file["format"], "xyz");
    EXPECT_DOUBLE_EQ(file["bounds"]["max"][2].get<double>(), 9.0);
}

TEST(Cli, BadInputGivesExitTwoAndOneLine) {
    TempDir dir;
    write_text(dir / "t.laz", "LASF whatever");
    write_text(dir / "trunc.ply",
               "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\n"
               "property float y\nproperty float z\nend_header\nabc");
    write_text(dir / "empty.xyz", "");
    for (const std::string name : {"t.laz", "trunc.ply", "empty.xyz", "missing.las"}) {
        const auto result = run_cli("info '" + (dir / name).string() + "'");
        EXPECT_EQ(result.exit_code, 2) << name;
        EXPECT_EQ(line_count(result.err), 1) << name << ": " << result.err;
        EXPECT_NE(result.err.find(name), std::string::npos) << result.err;
    }
    const auto directory = run_cli("info '" + dir.path().string() + "'");
    EXPECT_EQ(directory.exit_code, 2);
    // A .laz too short for a LAS header is reported as such (LAZ is read natively now).
    const auto laz = run_cli("info '" + (dir / "t.laz").string() + "'");
    EXPECT_NE(laz.err.find("shorter than the 227-byte LAS header"), std::string::npos) << laz.err;
}

// treelobes' own outputs: a .dbf6 tree with its levels of detail, a .forest of placed trees and a
// .tlobe lobe tree, each described from its contents (and as JSON); a damaged one is bad input.
TEST(Cli, InfoDescribesTreelobesOwnFiles) {
    TempDir dir;
    const auto sample = treelobes::test::source_dir() / "data" / "synthetic";
    const auto skeleton = sample / "ailanthus_altissima_5_skeleton.ply";
    ASSERT_EQ(run_cli("encode " + quoted(skeleton) + " --resolution 5 --lods 3 --out " + quoted(dir / "tree.dbf6")).exit_code, 0);
    write_text(dir / "trees.txt", skeleton.string() + " 10 20 1 90\n" + skeleton.string() + " 30 5 2\n");
    ASSERT_EQ(run_cli("encode --forest " + quoted(dir / "trees.txt") + " --resolution 5 --out " + quoted(dir / "stand.forest")).exit_code,
              0);
    ASSERT_EQ(run_cli("lobes " + quoted(sample / "birch_3.las") + " --species birch --out " + quoted(dir.path())).exit_code, 0);

    const auto human =
            run_cli("info " + quoted(dir / "tree.dbf6") + " " + quoted(dir / "stand.forest") + " " + quoted(dir / "birch_3.tlobe"));
    ASSERT_EQ(human.exit_code, 0) << human.err;
    for (const char* text : {"tree, .dbf6 version", "LOD 2:", "forest, .forest version", "2 trees in", "lobe tree, .tlobe version",
                             "species birch", "main skeleton:"})
        EXPECT_NE(human.out.find(text), std::string::npos) << text << "\n" << human.out;

    const auto r =
            run_cli("--json info " + quoted(dir / "tree.dbf6") + " " + quoted(dir / "stand.forest") + " " + quoted(dir / "birch_3.tlobe"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto files = nlohmann::json::parse(r.out)["files"];
    ASSERT_EQ(files.size(), 3u);
    const auto& tree = files[0];
    EXPECT_EQ(tree["code"], "DBF6");
    ASSERT_EQ(tree["lods"].size(), 3u);
    EXPECT_GT(tree["lods"][0]["internodes"].get<int>(), tree["lods"][2]["internodes"].get<int>());
    EXPECT_GT(tree["skeleton"]["total_length"].get<double>(), 10.0);
    const auto& forest = files[1];
    ASSERT_EQ(forest["trees"].size(), 2u);
    EXPECT_DOUBLE_EQ(forest["trees"][0]["position"][0].get<double>(), 10.0);
    EXPECT_NEAR(forest["trees"][0]["azimuth_deg"].get<double>(), 90.0, 1e-4);
    EXPECT_DOUBLE_EQ(forest["tree_positions"]["max"][0].get<double>(), 30.0);
    const auto& lobes = files[2];
    EXPECT_EQ(lobes["species"], "birch");
    EXPECT_GE(lobes["lobes"]["count"].get<int>(), 1);
    EXPECT_GT(lobes["lobes"]["faces"].get<int>(), 0);
    EXPECT_GT(lobes["bounds"]["max"][2].get<double>(), 5.0);  // a 9 m birch

    std::ifstream in(dir / "tree.dbf6", std::ios::binary);
    std::string bytes{std::istreambuf_iterator<char>(in), {}};
    bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x5a);
    write_text(dir / "damaged.dbf6", bytes);
    const auto bad = run_cli("info " + quoted(dir / "damaged.dbf6"));
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_EQ(line_count(bad.err), 1) << bad.err;
    EXPECT_EQ(run_cli("info " + quoted(dir / "tree.dbf6") + " --bounds 0,0,1,1").exit_code, 1);
}
