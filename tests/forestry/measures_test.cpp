// Forestry measures on clouds with known answers: a stem cylinder seen all round, from one
// side, or not at all; the trunks of a multi-stemmed tree; a cone crown; the cylinders of a two-node skeleton.
#include "forestry/measures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace treelobes::forestry {
namespace {

struct TreeCloud {
    std::vector<Eigen::Vector3f> points;
    std::vector<float> hag;  // flat terrain at z = 0
    void add(const Eigen::Vector3f& p) {
        points.push_back(p);
        hag.push_back(p.z());
    }
};

// Points on a vertical cylinder of `radius` around (cx, cy) from z = 0 to `height`, over the
// azimuths [0, arc) with 5 mm noise.
void add_stem(TreeCloud& cloud, double cx, double cy, double radius, double height, double arc, std::mt19937& random) {
    std::uniform_real_distribution<double> angle(0.0, arc), z(0.0, height);
    std::normal_distribution<double> noise(0.0, 0.005);
    for (int i = 0; i < 4000; ++i) {
        const double a = angle(random), r = radius + noise(random);
        cloud.add(Eigen::Vector3f(static_cast<float>(cx + r * std::cos(a)), static_cast<float>(cy + r * std::sin(a)),
                                  static_cast<float>(z(random))));
    }
}

// A solid cone of crown points from z0 up to z1, base radius `radius`, around (cx, cy).
void add_cone_crown(TreeCloud& cloud, double cx, double cy, double radius, double z0, double z1, std::mt19937& random) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 6000; ++i) {
        const double t = unit(random), a = 2 * std::numbers::pi * unit(random);
        const double r = radius * (1 - t) * std::sqrt(unit(random));
        cloud.add(Eigen::Vector3f(static_cast<float>(cx + r * std::cos(a)), static_cast<float>(cy + r * std::sin(a)),
                                  static_cast<float>(z0 + t * (z1 - z0))));
    }
}

TEST(Dbh, FullCylinderIsOkWithItsDiameter) {
    std::mt19937 random(1);
    TreeCloud cloud;
    add_stem(cloud, 3.0, -2.0, 0.15, 4.0, 2 * std::numbers::pi, random);
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {3.1, -2.1, 0.0});
    EXPECT_EQ(m.quality, DbhQuality::Ok) << m.reason;
    ASSERT_TRUE(m.diameter);
    EXPECT_NEAR(*m.diameter, 0.30, 0.01);
    EXPECT_NEAR(m.centre.x(), 3.0, 0.01);
    EXPECT_NEAR(m.centre.y(), -2.0, 0.01);
    EXPECT_GT(m.coverage, 0.9);
    EXPECT_EQ(m.stems, 1);
}

// Three trunks of 5-6 cm, 0.35 m from the tree's centre (a crape myrtle's): each its own circle,
// the tree's DBH the equivalent diameter of the three.
TEST(Dbh, AMultiStemmedTreeGivesTheEquivalentDiameterOfItsTrunks) {
    std::mt19937 random(5);
    TreeCloud cloud;
    const double radii[] = {0.05, 0.06, 0.055};
    for (int k = 0; k < 3; ++k) {
        const double a = 2 * std::numbers::pi * k / 3;
        add_stem(cloud, 1.0 + 0.35 * std::cos(a), 0.35 * std::sin(a), radii[k], 3.0, 2 * std::numbers::pi, random);
    }
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {1.0, 0.0, 0.0});
    EXPECT_EQ(m.quality, DbhQuality::Ok) << m.reason;
    EXPECT_EQ(m.stems, 3);
    ASSERT_TRUE(m.diameter);
    EXPECT_NEAR(*m.diameter, 2 * std::sqrt(0.05 * 0.05 + 0.06 * 0.06 + 0.055 * 0.055), 0.01);
    EXPECT_NEAR(m.centre.x(), 1.0, 0.01);
    EXPECT_NEAR(m.centre.y(), 0.0, 0.01);
}

// Three trunks of 5 cm from one collar, each leaning 20 degrees outward, with twigs on its outer
// side from 1.15 m up (a crape myrtle's): in the breast-height band each trunk is smeared by its
// lean and joined by its twigs, and the three circles give 19.1 cm for 17.3 (17.4-19.3 over 20
// random streams); followed down in thin layers each is 5 cm (17.4-17.6 cm over the same 20).
TEST(Dbh, LeaningTrunksWithTwigsAreMeasuredBelowTheTwigs) {
    std::mt19937 random(2);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.003);
    const double lean = std::tan(20.0 * std::numbers::pi / 180.0);
    TreeCloud cloud;
    for (int k = 0; k < 3; ++k) {
        const double out = 2 * std::numbers::pi * k / 3;
        const Eigen::Vector2d direction(std::cos(out), std::sin(out));
        const auto add = [&](double z, double a, double r) {
            const Eigen::Vector2d axis = (0.05 + lean * z) * direction;
            cloud.add(Eigen::Vector3f(static_cast<float>(axis.x() + r * std::cos(a)), static_cast<float>(axis.y() + r * std::sin(a)),
                                      static_cast<float>(z)));
        };
        for (int i = 0; i < 2000; ++i) add(2.0 * unit(random), 2 * std::numbers::pi * unit(random), 0.05 + noise(random));
        for (int i = 0; i < 200; ++i) add(1.15 + 0.85 * unit(random), out + 0.5 * (unit(random) - 0.5), 0.06 + 0.03 * unit(random));
    }
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {0.0, 0.0, 0.0});
    EXPECT_EQ(m.stems, 3) << m.reason;
    ASSERT_TRUE(m.diameter);
    EXPECT_NEAR(*m.diameter, 2 * std::sqrt(3.0) * 0.05, 0.006);
}

// A 15 cm trunk with a curtain of hanging twigs beside it that ends 1 m above the ground (a
// willow's): at breast height the curtain's bundle holds a circle like the trunk's, but it does
// not reach down. One stem.
TEST(Dbh, ATwigBundleBesideATrunkIsNotASecondStem) {
    std::mt19937 random(6);
    TreeCloud cloud;
    add_stem(cloud, 0.0, 0.0, 0.15, 4.0, 2 * std::numbers::pi, random);
    TreeCloud bundle;
    add_stem(bundle, 0.8, 0.0, 0.12, 2.0, 2 * std::numbers::pi, random);
    for (std::size_t k = 0; k < bundle.points.size(); k += 5)  // twigs, sparser than the trunk
        if (bundle.points[k].z() >= 1.0f) cloud.add(bundle.points[k]);
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {0.0, 0.0, 0.0});
    EXPECT_EQ(m.stems, 1);
    ASSERT_TRUE(m.diameter);
    EXPECT_NEAR(*m.diameter, 0.30, 0.01);
}

// A 0.6 m trunk seen from one side (a third of its circumference, about 65 points at breast
// height) with a dense bundle of its own sprouts in front of it (about 500 points at breast
// height, 11 cm across, ending 1.1 m above the ground): the bundle's circle holds more points,
// but only the trunk reaches the ground.
TEST(Dbh, ABundleOfSproutsInFrontOfATrunkSeenFromOneSideGivesWay) {
    std::mt19937 random(7);
    TreeCloud cloud;
    TreeCloud trunk;
    add_stem(trunk, 0.0, 0.0, 0.6, 3.0, 2 * std::numbers::pi / 3, random);
    for (std::size_t k = 0; k < trunk.points.size(); k += 4) cloud.add(trunk.points[k]);
    TreeCloud sprouts;
    add_stem(sprouts, 0.75, 0.35, 0.055, 1.6, 2 * std::numbers::pi, random);
    for (const Eigen::Vector3f& p : sprouts.points)
        if (p.z() >= 1.1f) cloud.add(p);
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {0.0, 0.0, 0.0});
    ASSERT_TRUE(m.diameter) << m.reason;
    EXPECT_EQ(m.quality, DbhQuality::PartialArc);
    EXPECT_NEAR(*m.diameter, 1.2, 0.05);
}

// A trunk flaring toward its root collar (radius 0.5 m from 1.2 m up, 1 m more per metre
// below), on a 20-degree slope, seen from its downhill half. Breast height above the terrain is
// an oblique cut there: about 1.1 m up the trunk in the middle of the arc, 1.3 m at its ends, and
// the circle through it measures 1.10 m (0.99-1.10 over 20 random streams). The diameter is that
// of a level cut 1.3 m above the ground at the stem's centre (1.00 m; 0.998-1.006 over the 20).
TEST(Dbh, AFlaredTrunkOnASlopeIsCutLevel) {
    const double slope = std::tan(20.0 * std::numbers::pi / 180.0);
    const auto radius_at = [](double z) { return 0.5 + 1.0 * std::max(0.0, 1.2 - z); };
    std::mt19937 random(12);
    std::uniform_real_distribution<double> angle(0.5 * std::numbers::pi, 1.5 * std::numbers::pi), height(0.0, 3.0);
    std::normal_distribution<double> noise(0.0, 0.005);
    TreeCloud cloud;
    for (int i = 0; i < 20000; ++i) {
        const double a = angle(random), z = height(random), r = radius_at(z) + noise(random);
        const Eigen::Vector3f p(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)), static_cast<float>(z));
        cloud.points.push_back(p);
        cloud.hag.push_back(static_cast<float>(z - slope * p.x()));  // the ground rises along +x through (0, 0, 0)
    }
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {0.0, 0.0, 0.0});
    ASSERT_TRUE(m.diameter) << m.reason;
    EXPECT_NEAR(*m.diameter, 2.0 * radius_at(1.3), 0.01);
    EXPECT_EQ(m.quality, DbhQuality::PartialArc);
}

TEST(Dbh, HalfArcIsPartial) {
    std::mt19937 random(2);
    TreeCloud cloud;
    add_stem(cloud, 0.0, 0.0, 0.2, 3.0, std::numbers::pi, random);
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {0.0, 0.0, 0.0});
    EXPECT_EQ(m.quality, DbhQuality::PartialArc) << m.reason;
    ASSERT_TRUE(m.diameter);
    EXPECT_NEAR(*m.diameter, 0.40, 0.03);
}

TEST(Dbh, NoStemPointsIsNotVisibleWithoutANumber) {
    std::mt19937 random(3);
    TreeCloud cloud;
    add_cone_crown(cloud, 0.0, 0.0, 3.0, 6.0, 15.0, random);  // an airborne tree: crown only
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {0.0, 0.0, 0.0});
    EXPECT_EQ(m.quality, DbhQuality::NotVisible);
    EXPECT_FALSE(m.diameter);
    EXPECT_EQ(m.stems, 0);
    EXPECT_FALSE(m.reason.empty());
    EXPECT_STREQ(dbh_quality_name(m.quality), "not_visible");
}

TEST(Dbh, ScatteredLeavesAtBreastHeightAreNotAStem) {
    std::mt19937 random(4);
    TreeCloud cloud;
    add_cone_crown(cloud, 0.0, 0.0, 1.5, 0.0, 3.0, random);  // a bush: points at 1.3 m but no circle
    const DbhMeasure m = measure_dbh(cloud.points, cloud.hag, {0.0, 0.0, 0.0});
    EXPECT_EQ(m.quality, DbhQuality::NotVisible);
    EXPECT_FALSE(m.diameter);
}

TEST(Crown, ConeCrownOverAStem) {
    std::mt19937 random(5);
    TreeCloud cloud;
    add_stem(cloud, 0.0, 0.0, 0.15, 6.0, 2 * std::numbers::pi, random);
    add_cone_crown(cloud, 0.0, 0.0, 3.0, 6.0, 15.0, random);
    const CrownMeasure m = measure_crown(cloud.points, {0.0, 0.0, 0.0});
    ASSERT_TRUE(m.base_height);
    EXPECT_NEAR(*m.base_height, 6.5, 0.7);  // the crown's lowest points more than 0.5 m from the stem
    ASSERT_TRUE(m.projected_area);
    EXPECT_NEAR(*m.projected_area, std::numbers::pi * 9.0, 0.1 * std::numbers::pi * 9.0);
    ASSERT_TRUE(m.diameter);
    EXPECT_NEAR(*m.diameter, 6.0, 0.3);
    ASSERT_TRUE(m.volume) << m.volume_failure;
    const double cone = std::numbers::pi * 9.0 * 9.0 / 3.0;  // 84.8 m^3
    EXPECT_GT(*m.volume, 0.7 * cone);
    EXPECT_LT(*m.volume, 1.2 * cone);
}

// The crown base and the crown volume's floor are heights above the ground at the stem (the
// base's z), like the tree's height: the same tree standing 100 m higher measures the same.
TEST(Crown, BaseHeightIsMeasuredFromTheGroundAtTheStem) {
    std::mt19937 random(6);
    TreeCloud cloud;
    add_stem(cloud, 0.0, 0.0, 0.15, 6.0, 2 * std::numbers::pi, random);
    add_cone_crown(cloud, 0.0, 0.0, 3.0, 6.0, 15.0, random);
    std::vector<Eigen::Vector3f> raised;
    for (const auto& p : cloud.points) raised.push_back(p + Eigen::Vector3f(0, 0, 100));
    const CrownMeasure low = measure_crown(cloud.points, {0.0, 0.0, 0.0});
    const CrownMeasure high = measure_crown(raised, {0.0, 0.0, 100.0});
    ASSERT_TRUE(low.base_height && high.base_height);
    EXPECT_NEAR(*high.base_height, *low.base_height, 1e-3);
    ASSERT_TRUE(low.volume && high.volume);
    EXPECT_NEAR(*high.volume, *low.volume, 1e-3 * *low.volume);
}

TEST(Crown, TooFewPointsGivesNoMeasures) {
    TreeCloud cloud;
    cloud.add({0, 0, 5});
    cloud.add({1, 0, 5});
    const CrownMeasure m = measure_crown(cloud.points, {0.0, 0.0, 0.0});
    EXPECT_FALSE(m.base_height);
    EXPECT_FALSE(m.volume);
    EXPECT_FALSE(m.diameter);
}

TEST(WoodyVolume, FrustaOfTheSkeleton) {
    TreeGraph skeleton;
    skeleton.add_node({0, 0, 0}, 0.2f, -1);
    skeleton.add_node({0, 0, 2}, 0.1f, 0);
    skeleton.add_node({1, 0, 2}, 0.1f, 1);
    const double frustum = std::numbers::pi / 3.0 * 2.0 * (0.04 + 0.02 + 0.01);
    const double cylinder = std::numbers::pi * 0.01 * 1.0;
    EXPECT_NEAR(woody_volume(skeleton), frustum + cylinder, 1e-6);
}

TEST(GroundUnder, MedianOfTheNearPointsGroundAndNoneFarAway) {
    // Points at 5 m above a ground z = 0.5 x; one with a wrong height (an outlier of the DTM).
    std::vector<Eigen::Vector3f> points;
    std::vector<float> heights;
    for (float x = -0.8f; x <= 0.81f; x += 0.2f) {
        points.emplace_back(x, 0.0f, 0.5f * x + 5.0f);
        heights.push_back(5.0f);
    }
    heights[0] = 1.0f;
    EXPECT_NEAR(*ground_under(points, heights, {0.0, 0.0}), 0.0, 0.11);  // the median, not the outlier's 4 m
    EXPECT_NEAR(*ground_under(points, heights, {0.8, 0.0}, 0.15), 0.4, 1e-5);
    EXPECT_FALSE(ground_under(points, heights, {5.0, 5.0}).has_value());
}

}  // namespace
}  // namespace treelobes::forestry
