// The per-tree pipeline of a tile (forestry/tree_pipeline.hpp): every tree in its own error
// boundary, trees too small for a model measured rather than dropped, the height on a slope and
// the stem position of a crown seen from above, with or without a limb reaching away.
#include "forestry/tree_pipeline.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace treelobes::forestry {
namespace {

// A stem of radius 0.15 m up to 5 m and a round crown of radius 2 m above it, on flat ground at z = 0.
TreeInput stem_and_crown(int id, std::size_t crown_points) {
    TreeInput tree;
    tree.id = id;
    std::mt19937 random(static_cast<unsigned>(id));
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    auto add = [&](const Eigen::Vector3f& p) {
        tree.points.positions.push_back(p);
        tree.height_above_ground.push_back(p.z());
    };
    for (float z = 0.05f; z < 5.0f; z += 0.05f)
        for (int k = 0; k < 12; ++k) {
            const float angle = static_cast<float>(k) * std::numbers::pi_v<float> / 6.0f;
            add({0.15f * std::cos(angle), 0.15f * std::sin(angle), z});
        }
    while (tree.points.size() < 1188 + crown_points) {
        const Eigen::Vector3f offset(unit(random), unit(random), unit(random));
        if (offset.norm() <= 1.0f) add(Eigen::Vector3f(0, 0, 6.5f) + 2.0f * offset);
    }
    return tree;
}

// `count` points at one spot: nothing a skeleton can be built from.
TreeInput collapsed(int id, std::size_t count) {
    TreeInput tree;
    tree.id = id;
    tree.points.positions.assign(count, Eigen::Vector3f(10, 10, 3));
    tree.height_above_ground.assign(count, 3.0f);
    return tree;
}

TEST(TreePipeline, ATreeThatFailsIsReportedAndTheOthersAreModelled) {
    const std::vector<TreeInput> trees{stem_and_crown(1, 800), collapsed(2, 200), stem_and_crown(3, 600)};
    std::vector<int> reported;
    std::size_t with_products = 0;
    const auto outcomes = process_trees(trees, {}, [&](const TreeOutcome& outcome, const TreeProducts* products) {
        reported.push_back(outcome.id);
        with_products += products ? 1 : 0;
    });
    ASSERT_EQ(outcomes.size(), 3u);
    EXPECT_EQ(reported.size(), 3u);
    EXPECT_EQ(with_products, 2u);
    for (int i : {0, 2}) {
        EXPECT_TRUE(outcomes[i].ok && outcomes[i].modelled) << outcomes[i].failure;
        EXPECT_GT(outcomes[i].skeleton.size(), 2u);
        EXPECT_NEAR(outcomes[i].measures.height, 8.5, 0.2);
        EXPECT_GT(outcomes[i].measures.woody_volume.value_or(0.0), 0.0);
    }
    EXPECT_FALSE(outcomes[1].ok);
    EXPECT_EQ(outcomes[1].id, 2);
    EXPECT_EQ(outcomes[1].failure_code, ExitCode::InvalidInput) << outcomes[1].failure;
    EXPECT_NE(outcomes[1].failure.find("tree 2"), std::string::npos) << outcomes[1].failure;
}

TEST(TreePipeline, HeightIsTheTopAboveTheGroundAtTheStemBase) {
    TreeInput tree = stem_and_crown(5, 800);
    for (std::size_t i = 0; i < tree.points.size(); ++i)  // ground z = x (45 degrees): the crown reaches over ground 2 m down
        tree.height_above_ground[i] = tree.points.positions[i].z() - tree.points.positions[i].x();
    const float largest_above_terrain = *std::max_element(tree.height_above_ground.begin(), tree.height_above_ground.end());
    TreeProducts products;
    const TreeOutcome outcome = process_tree(tree, {}, products);
    EXPECT_NEAR(outcome.measures.height, 8.5, 0.1);                   // the crown's top, 8.5 m above the base at z = 0
    EXPECT_GT(largest_above_terrain, outcome.measures.height + 0.5);  // what the largest height above the terrain would say
}

TEST(TreePipeline, ACrownSeenFromAboveIsPlacedAtItsCentreNotUnderItsTop) {
    TreeInput crown = stem_and_crown(6, 600);  // the crown alone: no stem points, no DBH
    crown.points.positions.erase(crown.points.positions.begin(), crown.points.positions.begin() + 1188);
    crown.height_above_ground.erase(crown.height_above_ground.begin(), crown.height_above_ground.begin() + 1188);
    crown.base = {1.5, 0.0, 0.0};  // an airborne base: under a top at the crown's edge
    crown.base_at_stem = false;
    TreeProducts products;
    const TreeOutcome placed = process_tree(crown, {}, products);
    EXPECT_NEAR(placed.measures.position.x(), 0.0, 0.2);
    EXPECT_NEAR(placed.measures.position.y(), 0.0, 0.2);
    EXPECT_FALSE(placed.measures.dbh.diameter.has_value());

    crown.base_at_stem = true;  // a base found at the stem is kept
    EXPECT_NEAR(process_tree(crown, {}, products).measures.position.x(), 1.5, 1e-9);
}

TEST(TreePipeline, ALimbReachingAwayDoesNotMoveACrownsStem) {
    TreeInput crown = stem_and_crown(7, 600);  // the crown alone, and a limb of 80 points 5-8 m east of it
    crown.points.positions.erase(crown.points.positions.begin(), crown.points.positions.begin() + 1188);
    crown.height_above_ground.erase(crown.height_above_ground.begin(), crown.height_above_ground.begin() + 1188);
    for (int k = 0; k < 80; ++k) {
        crown.points.positions.emplace_back(5.0f + 3.0f * static_cast<float>(k) / 80.0f, 0.0f, 6.0f);
        crown.height_above_ground.push_back(6.0f);
    }
    crown.base = {6.0, 0.0, 0.0};
    crown.base_at_stem = false;
    TreeProducts products;
    const TreeOutcome placed = process_tree(crown, {}, products);
    EXPECT_NEAR(placed.measures.position.x(), 0.0, 0.25);  // the plain mean x is 0.8 m
    EXPECT_NEAR(placed.measures.position.y(), 0.0, 0.2);
}

TEST(TreePipeline, ATreeTooSmallForAModelIsMeasuredOnly) {
    TreeInput small = stem_and_crown(4, 40);
    small.points.positions.erase(small.points.positions.begin(), small.points.positions.begin() + 1188);  // the crown alone
    small.height_above_ground.erase(small.height_above_ground.begin(), small.height_above_ground.begin() + 1188);
    TreePipelineOptions options;
    options.min_points = 50;
    TreeProducts products;
    const TreeOutcome outcome = process_tree(small, options, products);
    EXPECT_TRUE(outcome.ok);
    EXPECT_FALSE(outcome.modelled);
    EXPECT_EQ(outcome.measures.points, 40u);
    EXPECT_GT(outcome.measures.height, 5.0);
    EXPECT_FALSE(outcome.measures.woody_volume.has_value());
    EXPECT_TRUE(outcome.skeleton.empty());
    EXPECT_TRUE(products.tlobe.empty());

    options.min_points = 40;  // at the limit the tree is modelled
    const TreeOutcome modelled = process_tree(small, options, products);
    EXPECT_TRUE(modelled.modelled);
    EXPECT_FALSE(products.tlobe.empty());
}

}  // namespace
}  // namespace treelobes::forestry
