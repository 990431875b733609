// `treelobes compare A B`: a mesh against itself is identical by every figure; the same tree with
// its leaves drawn again keeps its crown outline while its raw silhouette changes, and another
// tree of the species does not; broken meshes exit 2 with one line, bad options exit 1.
#include "render/image.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>

using namespace treelobes;
using test::quoted;
using test::run_cli;
using test::TempDir;

namespace {

// A 6 m birch (24 000 leaves at leaf density 1; `leaf_density` times as many, each 1/sqrt of it
// as large: the same leaf area) as <dir>/birch_<seed>_mesh.obj.
std::filesystem::path small_birch(const TempDir& dir, int seed, double leaf_density) {
    const auto r = run_cli("synth tree --species birch --height 6 --angular-step 1 --mesh-format obj --seed " + std::to_string(seed) +
                           " --leaf-density " + std::to_string(leaf_density) + " --out " + quoted(dir.path()));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return dir / ("birch_" + std::to_string(seed) + "_mesh.obj");
}

nlohmann::json compare(const std::filesystem::path& a, const std::filesystem::path& b) {
    const auto r =
            run_cli("--json compare " + quoted(a) + " " + quoted(b) + " --compare-samples 3000 --silhouette-px 200 --crown-closing-px 4");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

const char* kViews[] = {"front", "side", "top"};

// Pixels of the crown picture's panels in the colour of one outline only (original only, rebuilt
// only); the legend strip below them (26 px) holds a key of each colour.
std::size_t one_sided_pixels(const render::Image& image) {
    std::size_t n = 0;
    for (int y = 0; y < image.height - 26; ++y)
        for (int x = 0; x < image.width; ++x) {
            const render::Rgba c = image.at(x, y);
            n += (c == render::Rgba{230, 120, 20, 255} || c == render::Rgba{40, 100, 200, 255});
        }
    return n;
}

}  // namespace

TEST(CompareCli, AMeshAgainstItselfIsIdentical) {
    TempDir dir;
    const auto mesh = small_birch(dir, 3, 1.0);
    const auto report = compare(mesh, mesh);
    ASSERT_FALSE(report.is_null());
    EXPECT_EQ(report["command"], "compare");
    EXPECT_EQ(report["a"]["triangles"], report["b"]["triangles"]);
    EXPECT_GT(report["a"]["leaf_area_m2"].get<double>(), 0);
    const auto& f = report["fidelity"];
    EXPECT_EQ(f["symmetric"]["max"].get<double>(), 0.0);
    EXPECT_EQ(f["leaf_area_ratio"].get<double>(), 1.0);
    for (const char* view : kViews) {
        EXPECT_EQ(f["silhouette_iou"][view].get<double>(), 1.0) << view;
        EXPECT_EQ(f["crown_silhouette_iou"][view].get<double>(), 1.0) << view;
    }
    const auto text = run_cli("compare " + quoted(mesh) + " " + quoted(mesh) + " --compare-samples 3000 --silhouette-px 100 --png " +
                              quoted(dir / "crowns.png"));
    ASSERT_EQ(text.exit_code, 0) << text.err;
    EXPECT_NE(text.out.find("crown outline IoU   front 1.00, side 1.00, top 1.00"), std::string::npos) << text.out;
    const render::Image crowns = render::read_png(dir / "crowns.png");
    EXPECT_EQ(crowns.width, 3 * 100);
    EXPECT_EQ(one_sided_pixels(crowns), 0u) << "one crown over itself: every pixel in both";
}

// The oracle of docs/rebuild.md in small: with other leaves on the same branches the crown
// outline stays (IoU near 1) while the raw silhouette loses pixels; another birch of the same
// height has another crown.
TEST(CompareCli, RedrawnLeavesKeepTheCrownOutlineAnotherTreeDoesNot) {
    TempDir dense, sparse, other;
    const auto a = small_birch(dense, 3, 1.0);
    const auto releafed = compare(a, small_birch(sparse, 3, 0.5));
    const auto b = small_birch(other, 4, 1.0);
    const auto different = compare(a, b);
    ASSERT_EQ(run_cli("compare " + quoted(a) + " " + quoted(b) + " --compare-samples 1000 --png " + quoted(other / "crowns.png")).exit_code,
              0);
    EXPECT_GT(one_sided_pixels(render::read_png(other / "crowns.png")), 1000u) << "two trees: outlines of their own";
    ASSERT_FALSE(releafed.is_null());
    ASSERT_FALSE(different.is_null());
    EXPECT_NEAR(releafed["fidelity"]["leaf_area_ratio"].get<double>(), 1.0, 0.1);
    for (const char* view : kViews) {
        const double raw = releafed["fidelity"]["silhouette_iou"][view].get<double>();
        const double crown = releafed["fidelity"]["crown_silhouette_iou"][view].get<double>();
        EXPECT_LT(raw, 1.0) << view;
        EXPECT_GE(crown, raw) << view;
        EXPECT_GT(crown, 0.9) << view;
        EXPECT_LT(different["fidelity"]["crown_silhouette_iou"][view].get<double>(), crown) << view;
    }
}

TEST(CompareCli, BrokenMeshesExitTwoWithOneLineBadOptionsOne) {
    TempDir dir;
    const auto good = small_birch(dir, 3, 1.0);
    const std::pair<const char*, const char*> cases[] = {
            {"truncated.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2"}, {"nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"},
            {"no_triangles.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"},   {"empty.obj", ""},
            {"point.obj", "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n"}, {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"},
    };
    for (const auto& [name, text] : cases) {
        test::write_text(dir / name, text);
        for (const bool first : {true, false}) {
            const auto r =
                    run_cli("compare " + (first ? quoted(dir / name) + " " + quoted(good) : quoted(good) + " " + quoted(dir / name)));
            EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err;
            const auto at = r.err.rfind("treelobes: error:");
            const std::string last = r.err.substr(at == std::string::npos ? 0 : at);
            EXPECT_NE(last.find(name), std::string::npos) << r.err;
            EXPECT_EQ(std::count(last.begin(), last.end(), '\n'), 1) << r.err;
        }
    }
    EXPECT_EQ(run_cli("compare " + quoted(dir / "absent.obj") + " " + quoted(good)).exit_code, 2);
    EXPECT_EQ(run_cli("compare " + quoted(good) + " " + quoted(good) + " --silhouette-px 8").exit_code, 1);
    EXPECT_EQ(run_cli("compare " + quoted(good)).exit_code, 1);
    EXPECT_EQ(run_cli("compare " + quoted(good) + " " + quoted(good) + " --png " + quoted(dir / "absent/crowns.png")).exit_code, 2);
}
