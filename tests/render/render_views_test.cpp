// Render views and colourings: panel shapes that fill the frame, colour ramps and tree ids, and
// `render --view --color` on the committed synthetic tile and skeleton.
#include "core/cloud_io.hpp"
#include "render/colour_map.hpp"
#include "render/image.hpp"
#include "render/rasterizer.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace treelobes;
using namespace treelobes::render;

namespace {

std::set<std::array<std::uint8_t, 4>> distinct_colours(const Image& image) {
    std::set<std::array<std::uint8_t, 4>> colours;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) colours.insert(image.at(x, y));
    return colours;
}

}  // namespace

TEST(RenderViews, AspectIsTheSubjectsShapeOnTheImage) {
    const Eigen::Vector3d lo(0, 0, 0), hi(4, 2, 8);
    EXPECT_NEAR(View::side(lo, hi, 0, 0).aspect(), 4.0 / 8.0, 1e-9);    // front: x across, z up
    EXPECT_NEAR(View::side(lo, hi, 270, 0).aspect(), 2.0 / 8.0, 1e-9);  // side: y across
    EXPECT_NEAR(View::side(lo, hi, 0, 90).aspect(), 4.0 / 2.0, 1e-9);   // top: x across, y up
}

TEST(RenderViews, RampAndIdColours) {
    EXPECT_EQ(ramp_colour(0.0), (Rgba{68, 1, 84, 255}));
    EXPECT_EQ(ramp_colour(1.0), (Rgba{253, 231, 37, 255}));
    EXPECT_EQ(ramp_colour(2.0), ramp_colour(1.0));                                                        // clamped
    for (double t = 0.1; t <= 1.0; t += 0.1) EXPECT_GT(ramp_colour(t)[1], ramp_colour(t - 0.1)[1]) << t;  // green rises
    EXPECT_EQ(id_colour(0), (Rgba{170, 170, 170, 255}));
    std::set<Rgba> ids;
    for (int id = 1; id <= 30; ++id) ids.insert(id_colour(id));
    EXPECT_EQ(ids.size(), 30u);
}

TEST(RenderViews, CliViewsAndColouringsFillTheFrame) {
    test::TempDir dir;
    const auto tile = test::source_dir() / "data" / "synthetic" / "tile" / "tile.las";
    const auto skeleton = test::source_dir() / "data" / "synthetic" / "birch_3_skeleton.ply";
    auto r = test::run_cli("render " + test::quoted(tile) + " --view top --color tree --size 200 --out " + test::quoted(dir / "top.png"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Image top = read_png(dir / "top.png");
    EXPECT_EQ(top.height, 200);
    const PointCloud cloud = read_point_cloud(tile);
    Eigen::Vector3f lo = cloud.positions.front(), hi = lo;
    for (const auto& p : cloud.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    EXPECT_NEAR(top.width, 200.0 * (hi.x() - lo.x()) / (hi.y() - lo.y()), 2);  // the tile's shape seen from above
    EXPECT_GT(distinct_colours(top).size(), 8u);                               // several trees, several colours

    r = test::run_cli("render " + test::quoted(skeleton) + " --view front --color order --size 300 --out " +
                      test::quoted(dir / "order.png"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Image front = read_png(dir / "order.png");
    EXPECT_NEAR(front.width, 300.0 * 4.53 / 8.97, 3);  // birch_3: 4.53 m wide (x), 8.97 m tall
    EXPECT_GE(distinct_colours(front).size(), 4u);     // background + orders 0..3

    r = test::run_cli("render " + test::quoted(skeleton) + " --view side --color tree --out " + test::quoted(dir / "x.png"));
    EXPECT_EQ(r.exit_code, 0) << r.err;  // colourings that do not apply leave the input plain
    r = test::run_cli("render " + test::quoted(skeleton) + " --view back --out " + test::quoted(dir / "x.png"));
    EXPECT_EQ(r.exit_code, 1);
}
