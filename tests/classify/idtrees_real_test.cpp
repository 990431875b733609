// The IDTReeS crowns (NEON airborne clips, ../shared/data/idtrees): every one of the 593 gets a
// feature vector, the crown extraction removes the ground, the understorey and the returns NEON
// classified as noise far above the canopy, and crowns too small for the shape groups keep the
// airborne group.
#include "classify/batch.hpp"
#include "classify/feature_table.hpp"
#include "classify/features.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace treelobes;
using namespace treelobes::classify;

TEST(ClassifyIdtreesReal, EveryCrownGetsFeaturesWithItsHeightAboveGround) {
    const auto labels_file = test::real_data("idtrees/labels.csv");
    const auto dir = labels_file.parent_path();
    std::vector<BatchInput> inputs;
    const auto labels = read_labels_csv(labels_file);
    for (const auto& l : labels) inputs.push_back({dir / l.id, l.id, ""});
    const FeatureBatch batch = compute_feature_batch(inputs, {});
    EXPECT_TRUE(batch.failures.empty()) << batch.failures.front().id << ": " << batch.failures.front().reason;
    ASSERT_EQ(batch.table.rows(), labels.size());
    const auto names = batch.table.feature_names;
    const auto column = [&](const char* name) {
        return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
    };
    std::size_t small = 0, noise = 0, ground = 0, ground_clips = 0;
    for (std::size_t r = 0; r < batch.table.rows(); ++r) {
        const double height = batch.table.at(r, column("als_height"));
        const CrownCounts& c = batch.crowns[r];
        // A few clips hold nothing but 2-7 ground returns (the lidar missed the tree): they are kept
        // whole and classified from that. The others: crowns 1 to 45 m above the ground; the
        // 90-143 m returns of 9 clips are gone.
        const bool ground_only = c.ground_found && c.ground == 0;
        ground_clips += ground_only;
        if (ground_only) {
            EXPECT_LT(height, 2.0) << batch.table.ids[r];
        } else {
            EXPECT_GT(height, 1.0) << batch.table.ids[r];
        }
        EXPECT_LT(height, 45.0) << batch.table.ids[r];
        EXPECT_TRUE(std::isfinite(batch.table.at(r, column("als_crown_radius")))) << batch.table.ids[r];
        EXPECT_TRUE(std::isfinite(batch.table.at(r, column(kScanDensityFeature)))) << batch.table.ids[r];
        if (!c.shape_features) {
            ++small;
            EXPECT_TRUE(std::isnan(batch.table.at(r, column("height")))) << batch.table.ids[r];
            EXPECT_TRUE(std::isfinite(batch.table.at(r, column("als_intensity_cv")))) << batch.table.ids[r];
        }
        noise += c.noise, ground += c.ground;
    }
    EXPECT_GT(small, 90u) << "crowns under 50 points are classified too, from their airborne features";
    EXPECT_GE(noise, 9u);
    EXPECT_LE(ground_clips, 10u);
    EXPECT_GT(ground, 40000u);
}
