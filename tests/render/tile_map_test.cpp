// The tile map's stem labels: placed around their marks without covering a mark or another
// label, the first marks first; on a crowded tile the ids that do not fit are left out.
#include "render/tile_map.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

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
