// End-to-end: `treelobes reconstruct` and `treelobes eval skeleton` on synthetic scans
// (outputs, JSON, resume, byte-identical re-runs, failures.jsonl and exit codes).
#include "core/cloud_io.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "support/synthetic_clouds.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

using namespace treelobes;
using test::run_cli;
using test::TempDir;

namespace {

std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

using test::quoted;

void write_y_tree(const std::filesystem::path& path) { write_point_cloud(test::cloud_from(test::y_tree(), 2500), path); }

}  // namespace

TEST(ReconstructCli, WritesTheFourOutputsAndASummary) {
    TempDir dir;
    write_y_tree(dir / "y.xyz");
    const auto r = run_cli("reconstruct " + quoted(dir / "y.xyz") + " --out " + quoted(dir / "out"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("y.xyz"), std::string::npos);
    const TreeGraph skeleton = read_skeleton_ply(dir / "out" / "y_skeleton.ply");
    EXPECT_EQ(skeleton.tip_count(), 2u);
    EXPECT_GT(read_mesh(dir / "out" / "y_branches.ply").face_count(), 100u);
    const PointCloud points = read_point_cloud(dir / "out" / "y_points.ply");
    ASSERT_NE(points.extra("internode"), nullptr);
    ASSERT_NE(points.extra("geodesic"), nullptr);
    for (double v : points.extra("internode")->values) EXPECT_LT(v, static_cast<double>(skeleton.size()));
    const auto summary = nlohmann::json::parse(slurp(dir / "out" / "y_summary.json"));
    EXPECT_EQ(summary["tree"]["branches"], 2);
    EXPECT_EQ(summary["quality"]["not_a_tree"], false);
    EXPECT_GT(summary["tree"]["height"].get<double>(), 2.8);
    EXPECT_TRUE(summary["seconds"].contains("total"));
    EXPECT_TRUE(summary.contains("peak_memory_mb"));
    EXPECT_EQ(summary["options"]["beta"], 1.5);
}

TEST(ReconstructCli, JsonResumeAndByteIdenticalReruns) {
    TempDir dir;
    write_y_tree(dir / "y.xyz");
    const std::string base = "reconstruct " + quoted(dir / "y.xyz") + " --out " + quoted(dir / "out");
    ASSERT_EQ(run_cli(base).exit_code, 0);
    const std::string skeleton = slurp(dir / "out" / "y_skeleton.ply");
    const std::string mesh = slurp(dir / "out" / "y_branches.ply");
    const std::string points = slurp(dir / "out" / "y_points.ply");
    // Finished trees are skipped on a re-run...
    const auto again = run_cli(base + " --json");
    ASSERT_EQ(again.exit_code, 0) << again.err;
    const auto json = nlohmann::json::parse(again.out);
    EXPECT_EQ(json["skipped"].size(), 1u);
    EXPECT_EQ(json["trees"].size(), 0u);
    // ...and redone identically with --overwrite.
    const auto redo = run_cli(base + " --overwrite --json");
    ASSERT_EQ(redo.exit_code, 0);
    EXPECT_EQ(nlohmann::json::parse(redo.out)["trees"].size(), 1u);
    EXPECT_EQ(slurp(dir / "out" / "y_skeleton.ply"), skeleton);
    EXPECT_EQ(slurp(dir / "out" / "y_branches.ply"), mesh);
    EXPECT_EQ(slurp(dir / "out" / "y_points.ply"), points);
    // Same with a different thread count.
    ASSERT_EQ(run_cli(base + " --overwrite --threads 1").exit_code, 0);
    EXPECT_EQ(slurp(dir / "out" / "y_skeleton.ply"), skeleton);
}

TEST(ReconstructCli, OneBadInputDoesNotStopTheOthers) {
    TempDir dir;
    write_y_tree(dir / "good.xyz");
    test::write_text(dir / "bad.xyz", "1 2 3\n4 5 6\n");  // two points: not a tree
    const auto r = run_cli("reconstruct " + quoted(dir / "bad.xyz") + " " + quoted(dir / "good.xyz") + " " + quoted(dir / "missing.xyz") +
                           " --out " + quoted(dir / "out"));
    EXPECT_EQ(r.exit_code, 3) << r.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / "good_skeleton.ply"));
    std::istringstream failures(slurp(dir / "out" / "failures.jsonl"));
    std::string line;
    int count = 0;
    while (std::getline(failures, line)) {
        const auto f = nlohmann::json::parse(line);
        EXPECT_TRUE(f.contains("reason"));
        ++count;
    }
    EXPECT_EQ(count, 2);
    // A single bad input is an input error (exit 2) with a one-line message.
    const auto single = run_cli("reconstruct " + quoted(dir / "bad.xyz") + " --out " + quoted(dir / "out2"));
    EXPECT_EQ(single.exit_code, 2);
    EXPECT_EQ(std::count(single.err.begin(), single.err.end(), '\n'), 1) << single.err;
    // Bad options are usage errors.
    EXPECT_EQ(run_cli("reconstruct " + quoted(dir / "good.xyz") + " --out " + quoted(dir / "o3") + " --species no_such_tree").exit_code, 1);
    EXPECT_EQ(run_cli("reconstruct " + quoted(dir / "good.xyz") + " --out " + quoted(dir / "o3") + " --beta -1").exit_code, 1);
    EXPECT_EQ(run_cli("reconstruct " + quoted(dir / "good.xyz")).exit_code, 1);  // --out missing
}

TEST(ReconstructCli, SpeciesSetsBetaGammaAndFs) {
    TempDir dir;
    write_y_tree(dir / "y.xyz");
    const auto r = run_cli("reconstruct " + quoted(dir / "y.xyz") + " --out " + quoted(dir / "out") + " --species pine --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto options = nlohmann::json::parse(r.out)["trees"][0]["options"];
    EXPECT_EQ(options["species"], "pine");
    EXPECT_DOUBLE_EQ(options["beta"].get<double>(), 1.3);  // Livny et al. 2011, Table 1
    EXPECT_DOUBLE_EQ(options["gamma"].get<double>(), 1.2);
    EXPECT_DOUBLE_EQ(options["fs"].get<double>(), 0.98);
    // An explicit flag overrides the species value.
    const auto o = run_cli("reconstruct " + quoted(dir / "y.xyz") + " --out " + quoted(dir / "out") +
                           " --species pine --beta 2 --overwrite --json");
    EXPECT_DOUBLE_EQ(nlohmann::json::parse(o.out)["trees"][0]["options"]["beta"].get<double>(), 2.0);
}

TEST(EvalCli, SkeletonAgainstItselfAndBadReference) {
    TempDir dir;
    write_y_tree(dir / "y.xyz");
    ASSERT_EQ(run_cli("reconstruct " + quoted(dir / "y.xyz") + " --out " + quoted(dir / "out")).exit_code, 0);
    const auto skeleton = dir / "out" / "y_skeleton.ply";
    const auto r = run_cli("eval skeleton --skeleton " + quoted(skeleton) + " --reference " + quoted(skeleton) + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto json = nlohmann::json::parse(r.out);
    EXPECT_LT(json["skeleton_to_reference"]["max"].get<double>(), 1e-5);
    EXPECT_EQ(json["components"], 1);
    EXPECT_DOUBLE_EQ(json["length_ratio"].get<double>(), 1.0);
    const auto human = run_cli("eval skeleton --skeleton " + quoted(skeleton) + " --reference " + quoted(skeleton));
    EXPECT_NE(human.out.find("median"), std::string::npos);
    test::write_text(dir / "broken.txt", "1 2\n");
    const auto bad = run_cli("eval skeleton --skeleton " + quoted(skeleton) + " --reference " + quoted(dir / "broken.txt"));
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
}

// The demo's single-tree score (scripts/demo.sh): the leaf-off sample reconstructed and scored
// against the part of its true skeleton the scan sees, trunks compared at breast height.
TEST(EvalCli, TheDemosLeafOffSampleScoresWell) {
    TempDir dir;
    const auto sample = test::source_dir() / "data" / "synthetic";
    const auto rec = run_cli("reconstruct " + quoted(sample / "ailanthus_altissima_5.las") + " --species ailanthus_altissima --out " +
                             quoted(dir / "out"));
    ASSERT_EQ(rec.exit_code, 0) << rec.err;
    const std::string eval = "eval skeleton --skeleton " + quoted(dir / "out" / "ailanthus_altissima_5_skeleton.ply") + " --reference " +
                             quoted(sample / "ailanthus_altissima_5_skeleton.ply") + " --visible-in " +
                             quoted(sample / "ailanthus_altissima_5.las") + " --json";
    const auto r = run_cli(eval);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_LT(j["skeleton_to_reference"]["median"].get<double>(), 0.03);
    EXPECT_LT(j["reference_to_skeleton"]["median"].get<double>(), 0.03);
    // No shorter than what the scan saw well, no longer than all the wood it touched.
    EXPECT_GT(j["length_ratio"].get<double>(), 0.8);
    EXPECT_LT(j["length"].get<double>(), j["touched_reference_length"].get<double>());
    EXPECT_GE(j["branches"]["precision"].get<double>(), 0.8);
    EXPECT_DOUBLE_EQ(j["breast_height"].get<double>(), 1.3);
    EXPECT_LT(std::abs(j["trunk_radius_error"].get<double>()), 0.1);
    EXPECT_GE(j["branches"]["recall"].get<double>(), 0.9);
    EXPECT_GE(j["branches"]["reference_branches"].get<int>(), 10);
    // At the base the true skeleton's root node (wider than the trunk above) is compared instead.
    const auto base = nlohmann::json::parse(run_cli(eval + " --breast-height 0").out);
    EXPECT_GT(base["reference_trunk_radius"].get<double>(), j["reference_trunk_radius"].get<double>());
    const auto bad = run_cli(eval + " --breast-height -1");
    EXPECT_EQ(bad.exit_code, 1);  // a usage error
    EXPECT_NE(bad.err.find("--breast-height"), std::string::npos) << bad.err;
}

TEST(ReconstructCli, RecentreOptionsReachTheSummary) {
    TempDir dir;
    write_y_tree(dir / "y.xyz");
    auto recentred = [&](const std::string& flags) {
        const auto r = run_cli("reconstruct " + quoted(dir / "y.xyz") + " --out " + quoted(dir / "out") + " --overwrite " + flags);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        return nlohmann::json::parse(slurp(dir / "out" / "y_summary.json"))["tree"]["recentred_nodes"].get<int>();
    };
    EXPECT_EQ(recentred("--recentre false"), 0);
    EXPECT_GT(recentred("--recentre-inside-band 0 --recentre-max-spread 0.2"), 0);  // every thin node off its centre moves
    EXPECT_EQ(run_cli("reconstruct " + quoted(dir / "y.xyz") + " --out " + quoted(dir / "out") + " --recentre-max-spread 0").exit_code, 1);
}

// A stem with a crumb of bark cut off by a 0.3 m gap: --max-gap leaves it out of the skeleton,
// --max-gap-points keeps pieces at least that big, and the summary counts the points left out.
TEST(ReconstructCli, PiecesBeyondGapsAreCountedInTheSummary) {
    TempDir dir;
    const std::vector<test::Segment> truth{{{0, 0, 0}, {0, 0, 3}, 0.08f}, {{-0.45f, 0, 2.0f}, {-0.6f, 0, 2.15f}, 0.03f}};
    write_point_cloud(test::cloud_from(truth, 3000), dir / "t.xyz");
    auto beyond_gaps = [&](const std::string& flags) {
        const auto r = run_cli("reconstruct " + quoted(dir / "t.xyz") + " --out " + quoted(dir / "out") + " --overwrite " + flags);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        const auto summary = nlohmann::json::parse(slurp(dir / "out" / "t_summary.json"));
        return std::pair{summary["points"]["beyond_gaps"].get<int>(), summary["tree"]["tips"].get<int>()};
    };
    EXPECT_EQ(beyond_gaps(""), std::pair(0, 2));
    const auto [left_out, tips] = beyond_gaps("--max-gap 0.15");
    EXPECT_GT(left_out, 50);
    EXPECT_EQ(tips, 1);
    EXPECT_EQ(beyond_gaps("--max-gap 0.15 --max-gap-points 20"), std::pair(0, 2));
    EXPECT_EQ(run_cli("reconstruct " + quoted(dir / "t.xyz") + " --out " + quoted(dir / "out") + " --max-gap-points -3").exit_code, 1);
    const auto alone =
            run_cli("reconstruct " + quoted(dir / "t.xyz") + " --out " + quoted(dir / "out") + " --overwrite --max-gap-points 20");
    EXPECT_EQ(alone.exit_code, 1);
    EXPECT_NE(alone.err.find("--max-gap-points needs --max-gap"), std::string::npos) << alone.err;
}
