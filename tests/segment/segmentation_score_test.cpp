// The matching rule of score_segmentation: each tree must hold half of the other's points.
#include "segment/segmentation_score.hpp"

#include "core/error.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

using namespace treelobes;

TEST(SegmentationScore, MatchesTreesThatHoldHalfOfEachOther) {
    // Reference trees 1 (4 points), 2 (4 points), 3 (2 points, short); found: 7 covers tree 1,
    // 8 takes 2 points of tree 2 plus 3 stray points (holds 2 of 4 = half of tree 2, but tree 2
    // holds only 2 of its 5), 9 is a false tree.
    const std::vector<std::int32_t> reference = {1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 0, 0, 0, 0};
    const std::vector<std::int32_t> found = {7, 7, 7, 0, 8, 8, 0, 0, 0, 0, 8, 8, 8, 9};
    const std::vector<float> height = {12, 8, 3, 1, 25, 20, 4, 1, 4, 2, 6, 6, 6, 9};
    const SegmentationScore s = score_segmentation(reference, found, height, 5.0f);
    EXPECT_EQ(s.reference_trees, 2u);  // tree 3 is 4 m tall
    EXPECT_EQ(s.found_trees, 3u);
    EXPECT_EQ(s.matched, 1u);
    EXPECT_NEAR(s.precision, 1.0 / 3.0, 1e-12);
    EXPECT_NEAR(s.recall, 0.5, 1e-12);
    EXPECT_NEAR(s.f1, 0.4, 1e-12);
    EXPECT_NEAR(s.points_right, 3.0 / 8.0, 1e-12);
    EXPECT_EQ(s.by_height[1].reference, 1u);  // tree 1, 12 m
    EXPECT_EQ(s.by_height[1].matched, 1u);
    EXPECT_EQ(s.by_height[2].reference, 1u);  // tree 2, 25 m
    EXPECT_EQ(s.by_height[2].matched, 0u);
}

TEST(SegmentationScore, IdenticalLabelsScoreOneAndSizesMustAgree) {
    const std::vector<std::int32_t> ids = {1, 1, 2, 2, 0};
    const std::vector<std::int32_t> renamed = {5, 5, 4, 4, 0};
    const std::vector<float> height = {10, 6, 9, 7, 0};
    const SegmentationScore s = score_segmentation(ids, renamed, height, 5.0f);
    EXPECT_EQ(s.f1, 1.0);
    EXPECT_EQ(s.points_right, 1.0);
    const std::vector<float> short_heights = {1, 2};
    EXPECT_EQ(test::error_code_of([&] { score_segmentation(ids, renamed, short_heights, 5.0f); }), ExitCode::Internal);
}
