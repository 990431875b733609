#include "core/error.hpp"
#include "render/image.hpp"
#include "render/rasterizer.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

using namespace treelobes;
using namespace treelobes::render;

namespace {

TriangleMesh unit_square_at(double z) {
    TriangleMesh mesh;  // a 1 x 1 square in the x-z plane at depth y = z
    mesh.vertices = {
            {0, static_cast<float>(z), 0}, {1, static_cast<float>(z), 0}, {1, static_cast<float>(z), 1}, {0, static_cast<float>(z), 1}};
    mesh.faces = {{0, 1, 2}, {0, 2, 3}};
    return mesh;
}

}  // namespace

TEST(Render, PngRoundTripKeepsPixels) {
    test::TempDir dir;
    Image image(7, 5, {10, 20, 30, 255});
    image.set(3, 2, {200, 100, 50, 128});
    write_png(image, dir / "a.png");
    const Image back = read_png(dir / "a.png");
    EXPECT_EQ(back.width, 7);
    EXPECT_EQ(back.pixels, image.pixels);
    test::write_text(dir / "bad.png", "\x89PNG\r\n\x1a\n truncated");
    EXPECT_THROW(read_png(dir / "bad.png"), Error);
}

TEST(Render, SquareFillsTheFrameAndNearerSurfaceWins) {
    View view;  // looking along +y at the box of the squares
    view.lo = {0, 0, 0};
    view.hi = {1, 1, 1};
    view.margin = 0.0;
    Rasterizer r(40, 40, view);
    r.draw_mesh(unit_square_at(1.0), {255, 0, 0, 255});  // far
    r.draw_mesh(unit_square_at(0.0), {0, 0, 255, 255});  // near
    EXPECT_GT(r.covered_pixels(), 40u * 40u * 9 / 10);
    const Rgba centre = r.image().at(20, 20);
    EXPECT_GT(centre[2], 0);
    EXPECT_EQ(centre[0], 0);
}

TEST(Render, PointsAndSkeletonDrawWhereExpected) {
    View view = View::side({-1, -1, 0}, {1, 1, 2}, 0, 0);
    Rasterizer r(50, 50, view);
    TreeGraph tree;
    tree.add_node({0, 0, 0}, 0.1f, -1);
    tree.add_node({0, 0, 2}, 0.1f, 0);
    r.draw_skeleton(tree, {0, 0, 0, 255});
    // A vertical trunk at x = 0 covers the middle column from bottom to top.
    int dark = 0;
    for (int y = 0; y < 50; ++y) dark += r.image().at(25, y)[0] == 0 || r.image().at(24, y)[0] == 0;
    EXPECT_GT(dark, 40);
}
