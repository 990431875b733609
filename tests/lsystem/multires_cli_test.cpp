// `treelobes multires`: files written, --string, skeleton input, --json, errors and exit codes.
#include "core/skeleton_io.hpp"
#include "render/image.hpp"
#include "lsystem_test_util.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace treelobes;
using namespace treelobes::test;
using treelobes::lsystem::test_util::example;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& path) {
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace

TEST(MultiresCli, LSystemFileWritesChainLodsAndSummary) {
    TempDir dir;
    const auto r = run_cli("multires '" + example("honda_monopodial.lsys") + "' --out '" + (dir / "out").string() +
                           "' --lod 0 --lod 10 --lod 1023 --mesh");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("1024 LODs"), std::string::npos) << r.out;
    for (const char* file : {"chain.txt", "summary.json", "lod_0000.ply", "lod_0010.ply", "lod_1023.ply", "lod_1023.mesh.ply"})
        EXPECT_TRUE(fs::exists(dir / "out" / file)) << file;
    const auto summary = nlohmann::json::parse(slurp(dir / "out" / "summary.json"));
    EXPECT_EQ(summary["lod_count"], 1024);
    EXPECT_EQ(summary["internodes"], 1023);
    EXPECT_EQ(summary["metric"], "branching-length");
    EXPECT_EQ(summary["lods"][2]["nodes"], 1024);
    EXPECT_EQ(summary["lods"][0]["nodes"], 11);  // LOD 0: the trunk, 10 internodes
    // The skeleton of the full LOD is the interpreted tree.
    const TreeGraph full = read_skeleton_ply(dir / "out" / "lod_1023.ply");
    EXPECT_EQ(full.size(), 1024u);
    EXPECT_EQ(read_skeleton_ply(dir / "out" / "lod_0000.ply").size(), 11u);
}

TEST(MultiresCli, StringInputGivesTheSeedChain) {
    TempDir dir;
    const auto r = run_cli("multires --string 'C1[C2[C3][C4]][C5]' --length-modules C1,C2,C3,C4,C5 --all --out '" + (dir / "out").string() +
                           "' --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["lod_count"], 3);
    EXPECT_EQ(summary["lods"].size(), 3u);
    const std::string chain = slurp(dir / "out" / "chain.txt");
    EXPECT_NE(chain.find("node 0 root C1\nSAVE 0\nnode 1 lateral C2\nSAVE 1\nnode 2 lateral C3\nRESTORE 1\nnode 3 lateral "
                         "C4\nRESTORE 0\nnode 4 lateral C5\n"),
              std::string::npos)
            << chain;
}

TEST(MultiresCli, SkeletonPlyInput) {
    TempDir dir;
    TreeGraph tree;
    tree.origin = {500000.0, 4000000.0, 250.0};
    tree.add_node({0, 0, 0}, 0.2f, -1);
    tree.add_node({0, 0, 2}, 0.15f, 0);
    tree.add_node({0.5f, 0, 3}, 0.05f, 1);
    tree.add_node({0, 0.1f, 4}, 0.1f, 1);
    tree.add_node({-0.3f, 0, 4.5f}, 0.04f, 3);
    tree.add_node({0, 0, 5}, 0.05f, 3);
    tree.order_children_by_subtree_length();
    write_skeleton_ply(tree, dir / "tree.ply");
    const auto r = run_cli("multires '" + (dir / "tree.ply").string() + "' --out '" + (dir / "out").string() +
                           "' --all --metric descendants --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["input_kind"], "skeleton");
    EXPECT_EQ(summary["lod_count"], 3);  // three tips
    const TreeGraph full = read_skeleton_ply(dir / "out" / "lod_2.ply");
    ASSERT_EQ(full.size(), tree.size());
    EXPECT_NEAR(full.total_length(), tree.total_length(), 1e-4);
    EXPECT_EQ(full.origin, tree.origin);                                 // georeferenced input keeps its origin
    EXPECT_EQ(read_skeleton_ply(dir / "out" / "lod_0.ply").size(), 4u);  // root -> 1 -> 3 -> one tip
}

TEST(MultiresCli, BadInputAndUsageErrors) {
    TempDir dir;
    write_text(dir / "bad.lsys", "axiom: A\nA(l) -> B(x)\n");
    auto r = run_cli("multires '" + (dir / "bad.lsys").string() + "' --out '" + (dir / "o").string() + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("bad.lsys: line 2, column 11: unknown name 'x'"), std::string::npos) << r.err;
    r = run_cli("multires --string 'F[F' --out '" + (dir / "o").string() + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--string: a '[' is never closed"), std::string::npos) << r.err;
    r = run_cli("multires --string 'F[F]F' --lod 7 --out '" + (dir / "o").string() + "'");
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("--lod 7: the chain has 2 levels (0..1)"), std::string::npos) << r.err;
    r = run_cli("multires --string F --metric length --out '" + (dir / "o").string() + "'");
    EXPECT_EQ(r.exit_code, 1);
    r = run_cli("multires '" + example("honda_monopodial.lsys") + "' --define nope=1 --out '" + (dir / "o").string() + "'");
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("--define nope"), std::string::npos) << r.err;
    r = run_cli("multires '" + example("honda_monopodial.lsys") + "' --steps 30 --max-modules 100000 --out '" + (dir / "o").string() + "'");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("more than 100000 modules"), std::string::npos) << r.err;
    r = run_cli("multires --out '" + (dir / "o").string() + "'");
    EXPECT_EQ(r.exit_code, 1);
}

TEST(MultiresCli, OverridesStepsSeedAndDefines) {
    TempDir dir;
    const auto r =
            run_cli("multires '" + example("honda_monopodial.lsys") + "' --steps 4 -D r1=0.5 --out '" + (dir / "o").string() + "' --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["internodes"], 15);
    EXPECT_EQ(summary["lods"][1]["skeleton"], "lod_15.ply");  // 16 levels: two digits
    // The trunk ends at 1 + 0.5 + 0.25 + 0.125 (r1 = 0.5 instead of 0.9).
    const TreeGraph full = read_skeleton_ply(dir / "o" / "lod_15.ply");
    const bool trunk_top = std::any_of(full.nodes.begin(), full.nodes.end(),
                                       [](const TreeNode& n) { return (n.position - Eigen::Vector3f(0, 0, 1.875f)).norm() < 1e-5f; });
    EXPECT_TRUE(trunk_top);
    const auto a = run_cli("multires '" + example("stochastic_bush.lsys") + "' --seed 5 --out '" + (dir / "a").string() + "'");
    const auto b = run_cli("multires '" + example("stochastic_bush.lsys") + "' --seed 5 --out '" + (dir / "b").string() + "'");
    ASSERT_EQ(a.exit_code, 0) << a.err;
    EXPECT_EQ(slurp(dir / "a" / "chain.txt"), slurp(dir / "b" / "chain.txt"));  // deterministic
    EXPECT_EQ(slurp(dir / "a" / "summary.json").find("\"modules\""), slurp(dir / "b" / "summary.json").find("\"modules\""));
    const auto c = run_cli("multires '" + example("stochastic_bush.lsys") + "' --seed 6 --out '" + (dir / "c").string() + "'");
    ASSERT_EQ(c.exit_code, 0) << c.err;
    EXPECT_NE(slurp(dir / "a" / "chain.txt"), slurp(dir / "c" / "chain.txt"));  // another seed, another bush
}

TEST(MultiresCli, FoliageHierarchyTexturesAndAtlas) {
    TempDir dir;
    const std::string args =
            "multires '" + example("leafy_ternary.lsys") + "' --steps 3 --all --texture-threshold 0.05 --texture-planes --out '";
    const auto r = run_cli(args + (dir / "a").string() + "' --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    const auto& foliage = summary["foliage"];
    EXPECT_EQ(foliage["leaves"], 6 * 27 + 2 * (27 + 9));
    const std::size_t textured = foliage["textured_boxes"];
    ASSERT_GE(textured, 1u);
    EXPECT_LT(textured, foliage["boxes"].get<std::size_t>());  // the threshold leaves small boxes out
    EXPECT_EQ(foliage["textures"], 6 * textured);
    EXPECT_EQ(foliage["texture_bytes_rgba"], 6 * textured * 128 * 128 * 4);
    // The atlas holds every texture; each plane is also a 128 x 128 PNG that is not empty.
    const render::Image atlas = render::read_png(dir / "a" / "atlas.png");
    const int columns = foliage["atlas_columns"];
    EXPECT_EQ(atlas.width, columns * 128);
    EXPECT_EQ(atlas.height, static_cast<int>((6 * textured + columns - 1) / columns) * 128);
    const auto hierarchy = nlohmann::json::parse(slurp(dir / "a" / "foliage.json"));
    ASSERT_EQ(hierarchy["boxes"].size(), foliage["boxes"].get<std::size_t>());
    const auto& root = hierarchy["boxes"][0];
    ASSERT_TRUE(root["textured"].get<bool>());
    ASSERT_EQ(root["planes"].size(), 6u);
    const render::Image z1 = render::read_png(dir / "a" / root["planes"][0]["png"].get<std::string>());
    EXPECT_EQ(z1.width, 128);
    std::size_t opaque = 0;
    for (int y = 0; y < z1.height; ++y)
        for (int x = 0; x < z1.width; ++x) opaque += z1.at(x, y)[3] > 0;
    EXPECT_GT(opaque, 500u);
    EXPECT_LT(opaque, 128u * 128u);
    // Foliage-only levels refine the hierarchy: more boxes at each level.
    ASSERT_GE(foliage["levels"].size(), 2u);
    EXPECT_EQ(foliage["levels"][0]["boxes"], 1);
    EXPECT_GT(foliage["levels"][1]["boxes"].get<int>(), 1);
    // Combined LODs: geometry leaves + leaves in textures + omitted leaves = all leaves.
    for (const auto& lod : summary["lods"]) {
        EXPECT_EQ(lod["foliage"]["leaves_omitted"], 0);  // default: small branches as geometry
        const auto& f = lod["foliage"];
        EXPECT_EQ(f["leaves_as_geometry"].get<std::size_t>() + f["leaves_in_textures"].get<std::size_t>() +
                          f["leaves_omitted"].get<std::size_t>(),
                  foliage["leaves"].get<std::size_t>());
        EXPECT_EQ(f["texture_quads"], 6 * f["textured_boxes"].size());
    }
    EXPECT_EQ(summary["lods"].back()["foliage"]["leaves_as_geometry"], foliage["leaves"]);
    EXPECT_GT(summary["lods"][0]["foliage"]["leaves_in_textures"].get<std::size_t>(), 0u);  // LOD 0: mostly textures
    // Omitting small branches' leaves keeps the count honest too.
    const auto omit = run_cli(args + (dir / "o").string() + "' --small-foliage omit --lod 20 --json");
    ASSERT_EQ(omit.exit_code, 1) << "--lod and --all exclude each other";
    const auto o2 = run_cli("multires '" + example("leafy_ternary.lsys") +
                            "' --steps 3 --texture-threshold 0.05 --lod 20 "
                            "--small-foliage omit --json --out '" +
                            (dir / "o").string() + "'");
    ASSERT_EQ(o2.exit_code, 0) << o2.err;
    const auto omitted = nlohmann::json::parse(o2.out);
    const auto& f20 = omitted["lods"][0]["foliage"];
    EXPECT_GT(f20["leaves_omitted"].get<std::size_t>(), 0u);
    EXPECT_EQ(f20["leaves_as_geometry"].get<std::size_t>() + f20["leaves_in_textures"].get<std::size_t>() +
                      f20["leaves_omitted"].get<std::size_t>(),
              foliage["leaves"].get<std::size_t>());
    // Same input, same files.
    ASSERT_EQ(run_cli(args + (dir / "b").string() + "'").exit_code, 0);
    EXPECT_EQ(slurp(dir / "a" / "atlas.png"), slurp(dir / "b" / "atlas.png"));
    EXPECT_EQ(slurp(dir / "a" / "foliage.json"), slurp(dir / "b" / "foliage.json"));
    // No leaves, no foliage outputs; a bad threshold is a usage error.
    ASSERT_EQ(run_cli("multires --string 'F[F]F' --out '" + (dir / "c").string() + "'").exit_code, 0);
    EXPECT_FALSE(fs::exists(dir / "c" / "atlas.png"));
    EXPECT_EQ(run_cli("multires --string 'F' --texture-threshold 1.5 --out '" + (dir / "d").string() + "'").exit_code, 1);
}
