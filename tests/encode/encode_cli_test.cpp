// `treelobes encode`, `lod` and `decode-code` end to end: the paper's vectors through the CLI,
// JSON summaries, exit codes and one-line errors.
#include "core/skeleton_io.hpp"
#include "paper_trees.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sstream>

using treelobes::test::run_cli;
using treelobes::test::TempDir;

namespace {

using treelobes::test::quoted;

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream stream(text);
    for (std::string line; std::getline(stream, line);) out.push_back(line);
    return out;
}

}  // namespace

TEST(EncodeCli, PrintsThePapersCodesForTheFig4Skeleton) {
    TempDir dir;
    treelobes::write_skeleton_ply(treelobes::test::fig4_tree(), dir / "fig4.ply");
    const std::string args = "encode " + quoted(dir / "fig4.ply") + " --resolution 3 --internode-length 1 --print-code";
    const auto dbf6 = run_cli(args);
    ASSERT_EQ(dbf6.exit_code, 0) << dbf6.err;
    EXPECT_EQ(lines(dbf6.out), (std::vector<std::string>{treelobes::test::kFig4DBF6, "10,9,6,3,4,3,2,1"}));
    const auto f6 = run_cli(args + " --f6");
    ASSERT_EQ(f6.exit_code, 0) << f6.err;
    EXPECT_EQ(lines(f6.out), (std::vector<std::string>{treelobes::test::kFig4F6, "10,9,6,3,4,3,2,1"}));
}

TEST(EncodeCli, JsonSummaryCarriesCodeLengthsAndGeometry) {
    TempDir dir;
    treelobes::write_skeleton_ply(treelobes::test::fig4_tree(), dir / "fig4.ply");
    const auto result = run_cli("--json encode " + quoted(dir / "fig4.ply") + " --resolution 3 --internode-length 1");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const auto json = nlohmann::json::parse(result.out);
    EXPECT_EQ(json["code"], treelobes::test::kFig4DBF6);
    EXPECT_EQ(json["f6_length"], 35);
    EXPECT_EQ(json["dbf6_length"], 26);
    EXPECT_EQ(json["internodes"], 8);
    EXPECT_EQ(json["tips"], 4);
    EXPECT_EQ(json["root_radius"], 12);
    EXPECT_NEAR(json["voxel_size"].get<double>(), 1.0 / 3.0, 1e-12);
    EXPECT_EQ(json["radii"], (std::vector<int>{10, 9, 6, 3, 4, 3, 2, 1}));
}

TEST(EncodeCli, LodPrintsTheReducedCodeAndRadii) {
    const auto result = run_cli("lod --code 1116634617133370011637333700047 --radii 10,9,5,2,2,4,2,2,1 --threshold 3");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    EXPECT_EQ(lines(result.out), (std::vector<std::string>{"11186348170011837", "10,9,5,2,4,2"}));
    const auto levels = run_cli("--json lod --code 1116634617133370011637333700047 --radii '10, 9,5,2,2,4,2,2,1' --levels 4");
    ASSERT_EQ(levels.exit_code, 0) << levels.err;
    const auto json = nlohmann::json::parse(levels.out);
    ASSERT_EQ(json["levels"].size(), 4u);
    // Thresholds from the laterals' first radii 2, 4, 2, 1 (unique 1 2 4): 1, 2, 4. The last
    // level is the paper's C' of Fig. 7 (its T = 3 prunes the same branches).
    EXPECT_EQ(json["levels"][1]["threshold"], 1.0);
    EXPECT_EQ(json["levels"][2]["threshold"], 2.0);
    EXPECT_EQ(json["levels"][3]["threshold"], 4.0);
    EXPECT_EQ(json["levels"][1]["code"], "1116634617133370011637333700047");
    EXPECT_EQ(json["levels"][2]["code"], "11166346171333700118373337");
    EXPECT_EQ(json["levels"][3]["code"], "11186348170011837");
}

TEST(EncodeCli, DecodeCodeWritesASkeletonThatEncodesToTheSameCode) {
    TempDir dir;
    const auto decoded =
            run_cli(std::string("decode-code --code ") + treelobes::test::kFig4F6 +
                    " --radii 10,9,6,3,4,3,2,1 --f6 --resolution 3 --internode-length 1 --root-radius 12 --out " + quoted(dir / "out.ply"));
    ASSERT_EQ(decoded.exit_code, 0) << decoded.err;
    const treelobes::TreeGraph tree = treelobes::read_skeleton_ply(dir / "out.ply");
    EXPECT_EQ(tree.size(), 9u);
    EXPECT_FLOAT_EQ(tree.nodes[0].radius, 0.012f);
    const auto again = run_cli("encode " + quoted(dir / "out.ply") + " --resolution 3 --internode-length 1 --print-code");
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(lines(again.out)[0], treelobes::test::kFig4DBF6);
}

TEST(EncodeCli, CorruptCodesExitWithTwoAndOneLine) {
    TempDir dir;
    const std::string out = " --resolution 3 --internode-length 1 --out " + quoted(dir / "x.ply");
    const struct {
        std::string args;
        std::string message;
    } cases[] = {
            {"decode-code --code 111917 --radii 1,2" + out, "unknown chain code symbol '9' at character 4"},
            {"decode-code --code 1118111 --radii 1,2" + out, "without the final branch tip 7"},
            {"decode-code --code 1118118117 --radii 1,2" + out, "radius list has 2 values but the DBF6 code has 3 internodes"},
            {"decode-code --code 11161117 --radii 1,2" + out, "fork(s) 6 without a lateral branch"},
            {"decode-code --code 1117 --radii 1x" + out, "--radii: value 1 ('1x') is not a non-negative integer"},
            {"lod --code 11161117 --radii 1,2 --threshold 2", "fork(s) 6 without a lateral branch"},
            {"encode " + quoted(dir / "missing.ply") + " --resolution 3", "missing.ply"},
    };
    for (const auto& c : cases) {
        const auto result = run_cli(c.args);
        EXPECT_EQ(result.exit_code, 2) << c.args;
        EXPECT_NE(result.err.find(c.message), std::string::npos) << c.args << "\n" << result.err;
        EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
        EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
    }
}

TEST(EncodeCli, BadOptionsExitWithOne) {
    TempDir dir;
    treelobes::write_skeleton_ply(treelobes::test::fig4_tree(), dir / "fig4.ply");
    const std::string file = quoted(dir / "fig4.ply");
    EXPECT_EQ(run_cli("encode " + file).exit_code, 1);  // --resolution is required
    EXPECT_EQ(run_cli("encode " + file + " --resolution 0").exit_code, 1);
    EXPECT_EQ(run_cli("encode " + file + " --resolution 3 --internode-length -2").exit_code, 1);
    EXPECT_EQ(run_cli("encode " + file + " --resolution 3 --internode-length often").exit_code, 1);
    EXPECT_EQ(run_cli("lod --code 1117 --radii 1").exit_code, 1);  // neither --threshold nor --levels
    EXPECT_EQ(run_cli("lod --code 1117 --radii 1 --threshold 2 --levels 3").exit_code, 1);
    EXPECT_EQ(run_cli("decode-code --code 1117 --radii 1 --resolution 3 --out x.ply").exit_code, 1);
}
