// `treelobes synth ...` end to end: outputs, byte-identical reruns, labels, errors.
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/skeleton_io.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sstream>

using namespace treelobes;
using treelobes::test::run_cli;
using treelobes::test::TempDir;

namespace {

using test::quoted;

const char* kFastTree = " --angular-step 0.4 --max-leaves 5000 --height 6";

}  // namespace

TEST(SynthCli, TreeWritesScanSkeletonMeshAndTruth) {
    TempDir dir;
    const auto r = run_cli("synth tree --species palm --seed 4 --out " + quoted(dir.path()) + kFastTree + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["species"], "palm");
    EXPECT_GT(summary["scan"]["points"].get<int>(), 1000);
    for (const char* suffix : {".las", "_skeleton.ply", "_mesh.ply", "_truth.json"})
        EXPECT_TRUE(std::filesystem::exists(dir / (std::string("palm_4") + suffix))) << suffix;
    const PointCloud cloud = read_las(dir / "palm_4.las");
    EXPECT_EQ(cloud.source.version, "1.4");
    ASSERT_NE(cloud.extra("treeID"), nullptr);
    ASSERT_NE(cloud.extra("internode"), nullptr);
    // Internode labels index the skeleton file's vertices.
    const TreeGraph skeleton = read_skeleton_ply(dir / "palm_4_skeleton.ply");
    double top = 0;
    for (double v : cloud.extra("internode")->values) top = std::max(top, v);
    EXPECT_LT(top, static_cast<double>(skeleton.size()));
    EXPECT_GT(top, 0);
}

TEST(SynthCli, SameSeedGivesByteIdenticalFiles) {
    TempDir a, b;
    const std::string args = " --species birch --seed 21 --scanner als --pulse-density 50 --max-leaves 5000 --height 8 --preview";
    ASSERT_EQ(run_cli("synth tree --out " + quoted(a.path()) + args).exit_code, 0);
    ASSERT_EQ(run_cli("synth tree --out " + quoted(b.path()) + args + " --threads 1").exit_code, 0);
    for (const char* file : {"birch_21.las", "birch_21_skeleton.ply", "birch_21_mesh.ply", "birch_21_truth.json", "birch_21_mesh.png",
                             "birch_21_preview.png", "birch_21_scan.png"})
        EXPECT_EQ(read_file(a / file), read_file(b / file)) << file;

    TempDir c;
    ASSERT_EQ(run_cli("synth tree --out " + quoted(c.path()) +
                      " --species birch --seed 22 --scanner als --pulse-density 50 --max-leaves 5000 --height 8")
                      .exit_code,
              0);
    EXPECT_NE(read_file(a / "birch_21_skeleton.ply"), read_file(c / "birch_22_skeleton.ply"));
}

TEST(SynthCli, TileWritesLabelledLasTruthAndSkeletons) {
    TempDir dir;
    const auto r = run_cli("synth tile --trees 6 --size 25 --seed 3 --pulse-density 8 --max-leaves 3000 --out " + quoted(dir.path()));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const PointCloud cloud = read_las(dir / "tile.las");
    for (const char* name : {"treeID", "species", "wood"}) ASSERT_NE(cloud.extra(name), nullptr) << name;
    EXPECT_EQ(cloud.extra("treeID")->type, AttributeType::Int32);
    std::set<int> ids, classes;
    for (double v : cloud.extra("treeID")->values) ids.insert(static_cast<int>(v));
    for (auto c : cloud.classification) classes.insert(c);
    EXPECT_TRUE(classes.count(2));  // ground
    EXPECT_TRUE(classes.count(5));  // trees
    EXPECT_GE(ids.size(), 6u);
    const std::string truth = read_file(dir / "truth.csv");
    EXPECT_EQ(std::count(truth.begin(), truth.end(), '\n'), 7);
    for (int id = 1; id <= 6; ++id) EXPECT_TRUE(std::filesystem::exists(dir / "skeletons" / ("tree_" + std::to_string(id) + ".ply")));
    // Skeletons are in the tile frame: their roots lie inside the tile.
    const TreeGraph first = read_skeleton_ply(dir / "skeletons" / "tree_1.ply");
    EXPECT_GE(first.nodes[0].position.x(), 0.0f);
    EXPECT_LE(first.nodes[0].position.x(), 25.0f);
    EXPECT_TRUE(std::filesystem::exists(dir / "summary.json"));
}

TEST(SynthCli, DatasetWritesLabelsAndResumes) {
    TempDir dir;
    const std::string args =
            "synth dataset --per-species 2 --species pine palm --seed 5 --angular-step 0.5 --max-leaves 3000 --out " + quoted(dir.path());
    const auto first = run_cli(args);
    ASSERT_EQ(first.exit_code, 0) << first.err;
    const std::string labels = read_file(dir / "labels.csv");
    EXPECT_EQ(std::count(labels.begin(), labels.end(), '\n'), 5);
    EXPECT_NE(labels.find("pine/pine_1.las,pine,8,"), std::string::npos) << labels;
    EXPECT_TRUE(std::filesystem::exists(dir / "palm" / "palm_0_skeleton.ply"));
    // A rerun keeps the finished trees and gives the same labels.
    const auto second = run_cli(args + " --json");
    ASSERT_EQ(second.exit_code, 0) << second.err;
    EXPECT_EQ(nlohmann::json::parse(second.out)["trees"]["kept"], 4);
    EXPECT_EQ(read_file(dir / "labels.csv"), labels);
}

TEST(SynthCli, BadInputGivesOneLineErrors) {
    TempDir dir;
    auto r = run_cli("synth tree --species baobab --out " + quoted(dir.path()));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("unknown species 'baobab'"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

    r = run_cli("synth tree --species pine --sub-rays 5 --out " + quoted(dir.path()));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("sub-rays"), std::string::npos) << r.err;

    test::write_text(dir / "bad.yaml", "version: 1\ndefaults: {reconstruction: {beta: 1, gamma: 1, fs: 1}}\nspecies: []\n");
    r = run_cli("synth tree --species pine --species-file " + quoted(dir / "bad.yaml") + " --out " + quoted(dir.path()));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("bad.yaml"), std::string::npos) << r.err;

    r = run_cli("synth tile --trees 300 --size 6 --species oak --out " + quoted(dir.path()));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("overlapping trunks"), std::string::npos) << r.err;
}
