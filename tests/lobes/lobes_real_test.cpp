// End to end on real scans: library (lobes closed, .tlobe under the 40 kB of Livny et al. 2011, Table 2, round trip)
// and the `treelobes lobes` CLI (outputs, summary, exit codes). Small scans only, to stay fast.
#include "geometry/closed_mesh.hpp"
#include "lobes/lobe_tree.hpp"
#include "lobes/tlobe_io.hpp"

#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

using namespace treelobes;
using namespace treelobes::lobes;

TEST(LobesReal, AdtreeTree13GivesClosedLobesInAFewKilobytes) {
    const auto path = test::real_data("adtree/tree13.xyz");
    const PointCloud cloud = read_point_cloud(path);
    ReconstructOptions ro;
    const TreeReconstruction r = reconstruct_tree(cloud, ro, path.string());
    LobeReport report;
    const LobeTree tree = build_lobe_tree(cloud, r, ro, "", {}, &report);
    ASSERT_GE(tree.lobes.size(), 1u);
    for (const Lobe& lobe : tree.lobes) {
        EXPECT_TRUE(check_closed(lobe.mesh).closed());
        EXPECT_GT(lobe.volume(), 0.0);
    }
    EXPECT_EQ(report.lobe_points + report.main_points,
              static_cast<std::size_t>(std::count_if(r.point_internode.begin(), r.point_internode.end(), [](int u) { return u >= 0; })));
    const std::string bytes = encode_tlobe(tree);
    EXPECT_LT(bytes.size(), 40000u);
    const LobeTree decoded = decode_tlobe(bytes, "tree13.tlobe");
    ASSERT_EQ(decoded.lobes.size(), tree.lobes.size());
    // The main skeleton is stored thinned (docs/tlobe.md), or whole with skeleton_tolerance 0.
    EXPECT_LT(decoded.skeleton.size(), tree.skeleton.size());
    TlobeOptions every_node;
    every_node.skeleton_tolerance = 0;
    EXPECT_EQ(decode_tlobe(encode_tlobe(tree, every_node), "whole.tlobe").skeleton.size(), tree.skeleton.size());
    // The file has room for the occupancy (a few kB of lobes): every cluster point is in an
    // occupied cell, on the grid the points can draw. AdTree's scan is sparse (6,283 lobe points,
    // 10-20 cm apart): 0.5 m cells hold 6 or more of them each on average, 0.4 m ones fewer.
    std::size_t points = 0, occupied = 0;
    for (std::size_t k = 0; k < decoded.lobes.size(); ++k) {
        const Lobe& lobe = decoded.lobes[k];
        EXPECT_TRUE(check_closed(lobe.mesh).closed());
        ASSERT_FALSE(lobe.occupancy.empty());
        EXPECT_NEAR(lobe.occupancy.cell, 0.5f, 1e-6f);
        for (const auto& p : tree.lobes[k].cluster_points) ASSERT_TRUE(lobe.occupancy.occupied(p));
        points += tree.lobes[k].cluster_points.size();
        occupied += lobe.occupancy.occupied_count();
    }
    EXPECT_GE(static_cast<double>(points) / static_cast<double>(occupied), TlobeOptions{}.min_points_per_cell);
    EXPECT_EQ(encode_tlobe(tree), bytes);  // deterministic
}

TEST(LobesReal, CliWritesTlobeMeshesAndSummary) {
    test::TempDir dir;
    const auto input = test::real_data("archi/tree1_points.las");
    const auto r = test::run_cli("lobes " + input.string() + " --out " + dir.path().string() + " --fs 0.8");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(read_file(dir / "tree1_points_lobes.json"));
    EXPECT_EQ(summary["lobe_count"], summary["closed_lobes"]);
    EXPECT_GE(summary["lobe_count"].get<int>(), 1);
    EXPECT_DOUBLE_EQ(summary["options"]["fs"].get<double>(), 0.8);
    const auto size = std::filesystem::file_size(dir / "tree1_points.tlobe");
    EXPECT_EQ(summary["tlobe_bytes"].get<std::size_t>(), size);
    EXPECT_LT(size, 40000u);
    EXPECT_TRUE(std::filesystem::exists(dir / "tree1_points_lobes.ply"));
    EXPECT_TRUE(std::filesystem::exists(dir / "tree1_points_main.ply"));
    EXPECT_EQ(read_tlobe(dir / "tree1_points.tlobe").lobes.size(), summary["lobe_count"].get<std::size_t>());
    // A smaller --budget-kb is kept: coarser occupancy, then simpler lobe surfaces (the same lobes);
    // the file options reach the writer (tree13 below: what --skeleton-tolerance does).
    const auto tight = test::run_cli("lobes " + input.string() + " --out " + (dir / "tight").string() +
                                     " --fs 0.8 --budget-kb 4 --skeleton-tolerance 0");
    ASSERT_EQ(tight.exit_code, 0) << tight.err;
    EXPECT_LE(std::filesystem::file_size(dir / "tight" / "tree1_points.tlobe"), 4000u);
    EXPECT_EQ(read_tlobe(dir / "tight" / "tree1_points.tlobe").lobes.size(), summary["lobe_count"].get<std::size_t>());
    EXPECT_EQ(nlohmann::json::parse(read_file(dir / "tight" / "tree1_points_lobes.json"))["options"]["skeleton_tolerance"], 0.0);

    // Synthesis from the file: full tree with fidelity metrics and preview, then a 25 % LOD.
    const std::string tlobe = (dir / "tree1_points.tlobe").string();
    const auto full = test::run_cli("synthesize " + tlobe + " --out " + (dir / "full.ply").string() + " --points " + input.string() +
                                    " --preview " + (dir / "full.png").string() + " --species lagerstroemia --max-triangles 1000000");
    ASSERT_EQ(full.exit_code, 0) << full.err;
    const auto f = nlohmann::json::parse(read_file(dir / "full.json"));
    EXPECT_EQ(f["species"], "lagerstroemia");
    EXPECT_GT(f["triangles"].get<std::size_t>(), 10000u);
    EXPECT_LE(f["triangles"].get<std::size_t>(), 1000000u);  // --max-triangles is a hard bound
    EXPECT_GT(f["patch_instances"].get<std::size_t>(), summary["lobe_count"].get<std::size_t>());
    EXPECT_LT(f["fidelity"]["median_point_to_mesh"].get<double>(), 0.4);  // covers the scan (measured 0.18 m)
    EXPECT_TRUE(std::filesystem::exists(dir / "full.png"));
    const auto lod = test::run_cli("synthesize " + tlobe + " --out " + (dir / "lod.ply").string() +
                                   " --lod 0.25 --species lagerstroemia --max-triangles 1000000");
    ASSERT_EQ(lod.exit_code, 0) << lod.err;
    const auto l = nlohmann::json::parse(read_file(dir / "lod.json"));
    EXPECT_LT(l["triangles"].get<std::size_t>(), f["triangles"].get<std::size_t>() / 2);
    EXPECT_TRUE(l["seconds"].contains("lod_extraction"));
    // The same seed gives the same mesh.
    const auto again = test::run_cli("synthesize " + tlobe + " --out " + (dir / "again.ply").string() +
                                     " --lod 0.25 --species lagerstroemia --max-triangles 1000000");
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_TRUE(read_file(dir / "again.ply") == read_file(dir / "lod.ply"));
}

TEST(LobesReal, CliExitCodes) {
    test::TempDir dir;
    EXPECT_EQ(test::run_cli("lobes " + (dir / "missing.xyz").string() + " --out " + dir.path().string()).exit_code, 2);
    const auto input = test::real_data("adtree/tree13.xyz");
    EXPECT_EQ(test::run_cli("lobes " + input.string() + " --out " + dir.path().string() + " --alpha-factor 0.5").exit_code, 1);
    EXPECT_EQ(test::run_cli("lobes " + input.string() + " --out " + dir.path().string() + " --skeleton-tolerance -0.01").exit_code, 1);
    EXPECT_EQ(test::run_cli("lobes " + input.string() + " --out " + dir.path().string() + " --bare-twig-length -1").exit_code, 1);
    test::write_text(dir / "bad.tlobe", "TLOB not really");
    const auto bad = test::run_cli("synthesize " + (dir / "bad.tlobe").string() + " --out " + (dir / "x.ply").string());
    EXPECT_EQ(bad.exit_code, 2);
    EXPECT_NE(bad.err.find("bad.tlobe"), std::string::npos) << bad.err;
}
