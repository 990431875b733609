#include "core/error.hpp"
#include "render/image.hpp"
#include "render/rasterizer.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

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

namespace {

// A width x height mask with the pixels where `inside(x, y)` holds.
template <class Inside>
std::vector<bool> mask_of(int width, int height, Inside inside) {
    std::vector<bool> mask(static_cast<std::size_t>(width) * height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) mask[static_cast<std::size_t>(y) * width + x] = inside(x, y);
    return mask;
}

bool in_disc(int x, int y, int cx, int cy, int r) { return (x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r; }

std::size_t count(const std::vector<bool>& mask) { return static_cast<std::size_t>(std::count(mask.begin(), mask.end(), true)); }

}  // namespace

// A crown drawn as scattered leaves (every third pixel of a disc) and the same disc with the
// leaves shifted by a pixel: as drawn they share no pixel, as crown outlines they are one disc
// (less a rim narrower than the spacing of the leaves, which the closing cannot reach beyond).
TEST(CrownOutline, BridgesGapsBetweenLeavesAndFillsTheCrown) {
    const int size = 100;
    const auto leaves = [&](int shift) {
        return mask_of(size, size, [&](int x, int y) { return in_disc(x, y, 50, 50, 30) && (x + shift) % 3 == 0 && y % 3 == 0; });
    };
    const auto a = leaves(0), b = leaves(1);
    EXPECT_EQ(silhouette_iou(a, b), 0.0);
    const auto crown_a = crown_outline(a, size, size, 3), crown_b = crown_outline(b, size, size, 3);
    EXPECT_GT(silhouette_iou(crown_a, crown_b), 0.9);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const bool inner = in_disc(x, y, 50, 50, 27), outer = !in_disc(x, y, 50, 50, 30);
            if (inner || outer) {
                EXPECT_EQ(crown_a[y * size + x], inner) << x << "," << y;
            }
        }
    EXPECT_EQ(crown_outline(a, size, size, 0), a) << "no closing and no enclosed hole: the mask as it is";
}

// An enclosed hole is filled whatever the closing; a notch open to the border is not, nor is the
// space between two crowns farther apart than the closing disc.
TEST(CrownOutline, FillsEnclosedHolesButKeepsOpenGapsAndSeparateCrowns) {
    const int size = 80;
    const auto ring = mask_of(size, size, [](int x, int y) { return in_disc(x, y, 40, 40, 30) && !in_disc(x, y, 40, 40, 20); });
    const auto filled = crown_outline(ring, size, size, 0);
    EXPECT_TRUE(filled[40 * size + 40]);
    EXPECT_EQ(count(filled), count(mask_of(size, size, [](int x, int y) { return in_disc(x, y, 40, 40, 30); })));

    const auto two = mask_of(size, size, [](int x, int y) { return in_disc(x, y, 15, 40, 10) || in_disc(x, y, 65, 40, 10); });
    const auto outline = crown_outline(two, size, size, 5);
    EXPECT_FALSE(outline[40 * size + 40]) << "30 px apart: two crowns, not one";
    EXPECT_EQ(count(outline), count(two));
    EXPECT_THROW(crown_outline(two, size, size - 1, 5), Error);
}

namespace {

// Closing by a disc of radius r the slow way, every pixel of the disc tried, on the mask padded
// by r (pixels beyond the padded frame unset), then cropped: what crown_outline closes.
std::vector<bool> closed_by_trying_the_disc(const std::vector<bool>& mask, int width, int height, int r) {
    const int pw = width + 2 * r, ph = height + 2 * r;
    const auto at = [&](const std::vector<bool>& m, int x, int y) {
        return x >= 0 && y >= 0 && x < pw && y < ph && m[static_cast<std::size_t>(y) * pw + x];
    };
    std::vector<bool> padded(static_cast<std::size_t>(pw) * ph), grown(padded.size()), closed(padded.size());
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            padded[static_cast<std::size_t>(y + r) * pw + x + r] = mask[static_cast<std::size_t>(y) * width + x];
    for (int pass = 0; pass < 2; ++pass)
        for (int y = 0; y < ph; ++y)
            for (int x = 0; x < pw; ++x) {
                bool any = false, all = true;
                for (int dy = -r; dy <= r; ++dy)
                    for (int dx = -r; dx <= r; ++dx)
                        if (dx * dx + dy * dy <= r * r) {
                            const bool set = at(pass == 0 ? padded : grown, x + dx, y + dy);
                            any = any || set;
                            all = all && set;
                        }
                (pass == 0 ? grown : closed)[static_cast<std::size_t>(y) * pw + x] = pass == 0 ? any : all;
            }
    std::vector<bool> out(mask.size());
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) out[static_cast<std::size_t>(y) * width + x] = closed[static_cast<std::size_t>(y + r) * pw + x + r];
    return out;
}

}  // namespace

// The distance-transform closing gives exactly the closing by trying every pixel of the disc, on
// random masks of several densities and radii, crowns touching the frame included.
TEST(CrownOutline, ClosingEqualsTryingEveryPixelOfTheDisc) {
    std::mt19937 random(7);
    const int width = 47, height = 31;
    for (const double density : {0.05, 0.2, 0.5})
        for (const int r : {1, 2, 4, 9}) {
            std::bernoulli_distribution set(density);
            std::vector<bool> mask(static_cast<std::size_t>(width) * height);
            for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = set(random);
            EXPECT_EQ(crown_outline(mask, width, height, r),
                      crown_outline(closed_by_trying_the_disc(mask, width, height, r), width, height, 0))
                    << "density " << density << ", radius " << r;
        }
}

// The largest mask and disc the CLI allows (4096 px, 256 px) in one pass over the pixels: trying
// every pixel of the disc would take hours here.
TEST(CrownOutline, LargestMaskAndDiscTheCliAllows) {
    const int size = 4096;
    const auto two = mask_of(size, size, [](int x, int y) { return in_disc(x, y, 1400, 2048, 600) || in_disc(x, y, 2700, 2048, 600); });
    const auto outline = crown_outline(two, size, size, 256);
    EXPECT_TRUE(outline[static_cast<std::size_t>(2048) * size + 2050])
            << "a 100 px gap between two large crowns is bridged by a 256 px disc";
    EXPECT_FALSE(outline[static_cast<std::size_t>(100) * size + 100]);
}
