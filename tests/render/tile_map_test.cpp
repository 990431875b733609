// The tile map's stem labels: placed around their marks without covering a mark or another
// label, the first marks first; on a crowded tile the ids that do not fit are left out; "trees"
// that look like buildings drawn apart.
#include "render/tile_map.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <vector>

using namespace treelobes::render;

namespace {

bool overlap(const LabelBox& a, const LabelBox& b) {
    return a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;
}

bool covers(const LabelBox& box, const Eigen::Vector2i& mark, int radius) {
    return mark.x() + radius >= box.x && mark.x() - radius < box.x + box.width && mark.y() + radius >= box.y &&
           mark.y() - radius < box.y + box.height;
}

}  // namespace

TEST(TileMapLabels, SparseMarksAllGetTheirLabelToTheRight) {
    const std::vector<Eigen::Vector2i> marks = {{50, 50}, {200, 50}, {50, 200}};
    const std::vector<Eigen::Vector2i> sizes(marks.size(), Eigen::Vector2i(30, 12));
    const auto boxes = place_labels(400, 300, marks, 5, sizes);
    ASSERT_EQ(boxes.size(), 3u);
    for (std::size_t i = 0; i < marks.size(); ++i) {
        ASSERT_TRUE(boxes[i]);
        EXPECT_GT(boxes[i]->x, marks[i].x() + 5);  // right of its mark
        EXPECT_EQ(boxes[i]->width, 30);
    }
}

TEST(TileMapLabels, CrowdedMarksKeepTheirLabelsApartAndOffTheMarks) {
    // A 20 x 20 grid of marks 25 px apart: labels 30 px wide cannot all fit.
    std::vector<Eigen::Vector2i> marks;
    for (int j = 0; j < 20; ++j)
        for (int i = 0; i < 20; ++i) marks.emplace_back(40 + 25 * i, 40 + 25 * j);
    const std::vector<Eigen::Vector2i> sizes(marks.size(), Eigen::Vector2i(30, 12));
    const auto boxes = place_labels(560, 560, marks, 3, sizes);
    std::vector<LabelBox> placed;
    for (const auto& box : boxes)
        if (box) placed.push_back(*box);
    EXPECT_GT(placed.size(), marks.size() / 4);
    EXPECT_LT(placed.size(), marks.size());
    ASSERT_TRUE(boxes.front());  // the first mark is placed first
    for (std::size_t a = 0; a < placed.size(); ++a) {
        EXPECT_TRUE(placed[a].x >= 0 && placed[a].y >= 0 && placed[a].x + 30 <= 560 && placed[a].y + 12 <= 560);
        for (std::size_t b = a + 1; b < placed.size(); ++b) ASSERT_FALSE(overlap(placed[a], placed[b])) << a << " " << b;
        for (const auto& mark : marks) ASSERT_FALSE(covers(placed[a], mark, 3)) << a;
    }
}

TEST(TileMapLabels, OneSizePerMark) {
    const std::vector<Eigen::Vector2i> marks = {{5, 5}}, sizes;
    EXPECT_THROW(place_labels(10, 10, marks, 1, sizes), treelobes::Error);
}

// A "tree" that looks like a building is drawn in grey stripes, not in a tree's colour, and its
// stem mark is a ring: two flat squares of points, tree 1 a tree, tree 2 marked not_a_tree.
TEST(TileMap, ATreeThatIsNotOneIsDrawnInGreyStripesWithARing) {
    treelobes::PointCloud cloud;
    std::vector<int> ids;
    for (int id : {1, 2})
        for (int i = 0; i < 40; ++i)
            for (int j = 0; j < 40; ++j) {
                cloud.positions.emplace_back(static_cast<float>(id == 1 ? 0.0 : 30.0) + 0.25f * static_cast<float>(i),
                                             0.25f * static_cast<float>(j), 5.0f);
                ids.push_back(id);
            }
    const std::vector<TileMapStem> stems = {{1, {5.0, 5.0, 0.0}, false}, {2, {35.0, 5.0, 0.0}, true}};
    TileMapOptions options;
    options.labels = false;
    const Image image = draw_tile_map(cloud, ids, {}, stems, options);
    std::set<Rgba> left, right;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) (x < image.width / 2 ? left : right).insert(image.at(x, y));
    const auto channels_equal = [](const Rgba& c) { return std::abs(c[0] - c[1]) < 20 && std::abs(c[1] - c[2]) < 20; };
    EXPECT_TRUE(std::any_of(left.begin(), left.end(), [&](const Rgba& c) { return !channels_equal(c); }));            // a tree's hue
    for (const Rgba& c : right) EXPECT_TRUE(channels_equal(c)) << int(c[0]) << " " << int(c[1]) << " " << int(c[2]);  // greys only
    EXPECT_GE(right.size(), 3u);  // the stripes' two greys and the mark's black (and white)
    // The mark's centre: black for a tree, white (a ring) for a "tree" that is not one.
    const int pixels_per_metre = 20;  // the smallest pixel, 0.05 m, for a 40 m wide map of at most 1600 px
    const int cy = image.height - 1 - options.margin_px - 5 * pixels_per_metre;
    EXPECT_EQ(image.at(options.margin_px + 5 * pixels_per_metre, cy), (Rgba{0, 0, 0, 255}));
    EXPECT_EQ(image.at(options.margin_px + 35 * pixels_per_metre, cy), (Rgba{255, 255, 255, 255}));
}
