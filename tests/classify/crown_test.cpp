// The crown of an airborne clip (ground, understorey, noise and a bird far above removed) and the
// features of crowns too small for the shape groups: every tree gets a vector, with what cannot be
// computed marked missing.
#include "classify/crown.hpp"
#include "classify/features.hpp"
#include "support/test_support.hpp"
#include "core/random.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace treelobes;
using namespace treelobes::classify;

namespace {

void add_point(PointCloud& c, float x, float y, float z, std::uint8_t cls, std::uint16_t intensity = 100, std::uint8_t ret = 1,
               std::uint8_t returns = 1) {
    c.positions.emplace_back(x, y, z);
    c.classification.push_back(cls);
    c.intensity.push_back(intensity);
    c.return_number.push_back(ret);
    c.number_of_returns.push_back(returns);
}

// A clip as NEON gives it: ground returns at 300 m (class 2), a crown 12-20 m above the ground,
// understorey at 1-3 m, one noise point (class 7) and one unclassified return 170 m up.
PointCloud survey_clip(std::uint64_t seed) {
    Rng rng(seed);
    PointCloud c;
    // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
    // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
    for (int i = 0; i < 60; ++i) {
        const double z = 300.0f + rng.uniform(-0.1, 0.1), y = rng.uniform(-5, 5), x = rng.uniform(-5, 5);
        add_point(c, x, y, z, 2, 40);
    }
    for (int i = 0; i < 200; ++i) {
        const double r = 4 * std::sqrt(rng.uniform(0, 1)), a = rng.uniform(0, 6.283);
        const double top = 320 - 2 * r * r / 16;
        add_point(c, r * std::cos(a), r * std::sin(a), top - rng.uniform(0, 5), 5, 200, 1, 2);
    }
    for (int i = 0; i < 25; ++i) {
        const double z = 301.0f + rng.uniform(0, 2), y = rng.uniform(-3, 3), x = rng.uniform(-3, 3);
        add_point(c, x, y, z, 1, 80, 2, 2);
    }
    add_point(c, 1, 1, 299, 7);
    add_point(c, 0, 0, 490, 1);
    return c;
}

}  // namespace

TEST(ClassifyCrown, RemovesGroundUnderstoreyNoiseAndHighOutliers) {
    const PointCloud clip = survey_clip(1);
    const CrownExtraction crown = extract_crown(clip);
    EXPECT_EQ(crown.counts.input, clip.size());
    EXPECT_EQ(crown.counts.ground, 60u);
    EXPECT_EQ(crown.counts.noise, 1u);
    EXPECT_EQ(crown.counts.high_outliers, 1u);
    EXPECT_EQ(crown.counts.understorey, 25u);
    ASSERT_TRUE(crown.ground_z.has_value());
    EXPECT_NEAR(*crown.ground_z, 299.9f, 0.1f);
    EXPECT_EQ(crown.crown.size(), 200u);
    for (std::size_t i = 0; i < crown.crown.size(); ++i) {
        EXPECT_EQ(crown.crown.classification[i], 5);  // the attributes travel with the points
        EXPECT_GT(crown.crown.positions[i].z(), 310.0f);
        EXPECT_LT(crown.crown.positions[i].z(), 321.0f);
    }
    // Features: height above the lowest ground return, not the 190 m return of a bird.
    const auto names = feature_names();
    const auto v = compute_features(clip);
    const auto at = [&](const char* name) { return v[std::find(names.begin(), names.end(), name) - names.begin()]; };
    EXPECT_NEAR(at("als_height"), 20.0, 0.3);
    EXPECT_NEAR(at("als_intensity_ground_ratio"), 200.0 / 40.0, 1e-9);
    EXPECT_NEAR(at("als_single_share"), 0.0, 1e-12);
    EXPECT_NEAR(at("height"), 20.0, 0.5);
}

TEST(ClassifyCrown, UnclassifiedCloudsLoseOnlyHighOutliers) {
    PointCloud c;
    for (int i = 0; i < 100; ++i) c.positions.emplace_back(0.1f * (i % 10), 0.1f * (i / 10), 0.2f * i);
    c.positions.emplace_back(0.0f, 0.0f, 200.0f);
    const CrownExtraction crown = extract_crown(c);
    EXPECT_FALSE(crown.ground_z.has_value());
    EXPECT_EQ(crown.counts.high_outliers, 1u);
    EXPECT_EQ(crown.counts.understorey + crown.counts.ground + crown.counts.noise, 0u);
    EXPECT_EQ(crown.crown.size(), 100u);
}

// A crown of 6 points: no frame, normals or skeleton, but a height, a width and an intensity; the
// shape groups are missing (NaN), not zero and not an error.
TEST(ClassifyCrown, SixPointCrownStillHasHeightWidthAndIntensity) {
    PointCloud c;
    for (int i = 0; i < 4; ++i) add_point(c, static_cast<float>(i), 0.0f, 100.0f, 2, 50);
    const float crown[6][3] = {{0, 0, 115}, {1.5f, 0, 114}, {-1.5f, 0.5f, 113.5f}, {0, 1.5f, 114}, {0, -1.5f, 113}, {0.5f, 0.5f, 115.5f}};
    for (const auto& p : crown) add_point(c, p[0], p[1], p[2], 5, 150, 1, 1);
    CrownCounts counts;
    const auto v = compute_features(c, {}, "six.las", nullptr, &counts);
    EXPECT_FALSE(counts.shape_features);
    const auto& catalogue = feature_catalogue();
    ASSERT_EQ(v.size(), catalogue.size());
    int missing_shape = 0;
    for (std::size_t f = 0; f < v.size(); ++f) {
        if (catalogue[f].group != "airborne" && catalogue[f].group != "scan") missing_shape += std::isnan(v[f]);
        if (catalogue[f].group == "scan") {
            EXPECT_TRUE(std::isfinite(v[f]));
        }
    }
    EXPECT_EQ(missing_shape, static_cast<int>(std::count_if(catalogue.begin(), catalogue.end(), [](const FeatureInfo& f) {
                  return f.group != "airborne" && f.group != "scan";
              })));
    const auto names = feature_names();
    const auto at = [&](const char* name) { return v[std::find(names.begin(), names.end(), name) - names.begin()]; };
    EXPECT_NEAR(at("als_height"), 15.5, 1e-4);
    EXPECT_GT(at("als_crown_radius"), 1.0);
    EXPECT_NEAR(at("als_intensity_ground_ratio"), 3.0, 1e-9);
    EXPECT_NEAR(at("als_single_share"), 1.0, 1e-12);
    EXPECT_TRUE(std::isnan(at("als_rgb_red_chroma"))) << "no colours: missing";
    // Without any attribute the same crown still has its height and width.
    PointCloud bare;
    for (const auto& p : crown) bare.positions.emplace_back(p[0], p[1], p[2]);
    const auto b = compute_features(bare);
    EXPECT_GT(b[std::find(names.begin(), names.end(), "als_crown_radius") - names.begin()], 1.0);
    EXPECT_TRUE(std::isnan(b[std::find(names.begin(), names.end(), "als_intensity_cv") - names.begin()]));
    EXPECT_EQ(test::error_code_of([] { compute_features(PointCloud{}, {}, "empty.las"); }), ExitCode::InvalidInput);
}
