// The per-point labels both segmentations share: which points may be a tree's, and labels turned
// into numbered trees with their tops and bases.
#include "segment/tree_labels.hpp"

#include "toy_tiles.hpp"

#include <gtest/gtest.h>

using namespace treelobes;
using test::ToyTile;

namespace {

constexpr std::uint8_t kBuilding = 6;  // ASPRS building class

// Flat classified ground 4 x 4 m with a few labelled points above it: two trees (1, 3), a bush
// lower than a tree may be (2), a point of a building and one just above the ground.
struct LabelledTile {
    ToyTile tile = test::flat_ground(0, 4, 0, 4);
    std::vector<std::int32_t> labels;
    std::size_t building = 0, low = 0;

    LabelledTile() {
        test::classify_ground(tile);
        labels.assign(tile.cloud.size(), 0);
        add({1.0f, 1.0f, 3.0f}, 1);
        add({1.2f, 1.1f, 5.0f}, 1);  // tree 1's top
        add({3.0f, 3.0f, 1.0f}, 2);
        add({3.1f, 0.9f, 8.0f}, 3);  // tree 3's top
        add({3.0f, 1.0f, 4.0f}, 3);
        building = add({2.0f, 2.0f, 6.0f}, 0, kBuilding);
        low = add({2.5f, 2.5f, 0.1f}, 0);
    }
    std::size_t add(const Eigen::Vector3f& p, std::int32_t label, std::uint8_t classification = 1) {
        tile.add(p, label);
        tile.cloud.classification.push_back(classification);
        labels.push_back(label);
        return tile.cloud.size() - 1;
    }
};

TEST(TreeLabels, VegetationLeavesOutGroundBuildingsAndPointsNearTheGround) {
    const LabelledTile t;
    const Terrain terrain = analyse_terrain(t.tile.cloud, {});
    const std::vector<std::uint8_t> vegetation = vegetation_points(t.tile.cloud, terrain, 0.3f);
    for (std::size_t i = 0; i < t.tile.cloud.size(); ++i) {
        const bool tree_or_bush = t.labels[i] != 0;
        EXPECT_EQ(vegetation[i] != 0, tree_or_bush) << "point " << i;
    }
    EXPECT_FALSE(vegetation[t.building]);
    EXPECT_FALSE(vegetation[t.low]);
    const OccupiedCells cells = occupied_cells(t.tile.cloud, vegetation, 1.0f);
    EXPECT_EQ(cells.points, 5u);
    EXPECT_EQ(cells.cells, 4u);  // 1 m cells (1, 1) with two points, (3, 3), (3, 0) and (3, 1)
    EXPECT_DOUBLE_EQ(cells.density(1.0), 5.0 / 4.0);
}

TEST(TreeLabels, LabelsBecomeTreesInOrderAndTooLowOnesAreDropped) {
    LabelledTile t;
    const Terrain terrain = analyse_terrain(t.tile.cloud, {});
    std::vector<std::int32_t> ids = t.labels;
    const auto trees = collect_trees(t.tile.cloud, terrain, ids, 3, {}, {}, 2.0f);
    ASSERT_EQ(trees.size(), 2u);
    EXPECT_EQ(trees[0].id, 1);
    EXPECT_EQ(trees[0].points, 2u);
    EXPECT_FLOAT_EQ(trees[0].top.z(), 5.0f);
    EXPECT_EQ(trees[1].id, 2);  // label 3 renumbered after the bush was dropped
    EXPECT_FLOAT_EQ(trees[1].top.z(), 8.0f);
    // Without stems a tree stands on the ground below its top.
    EXPECT_FLOAT_EQ(trees[1].base.x(), 3.1f);
    EXPECT_FLOAT_EQ(trees[1].base.y(), 0.9f);
    EXPECT_NEAR(trees[1].base.z(), 0.0f, 0.01f);
    EXPECT_EQ(trees[1].stem_radius, 0.0f);
    for (std::size_t i = 0; i < ids.size(); ++i) {
        const std::int32_t expected = t.labels[i] == 1 ? 1 : t.labels[i] == 3 ? 2 : 0;
        EXPECT_EQ(ids[i], expected) << "point " << i;
    }
}

TEST(TreeLabels, ATreeWithAStemStandsOnIt) {
    LabelledTile t;
    const Terrain terrain = analyse_terrain(t.tile.cloud, {});
    std::vector<std::int32_t> ids = t.labels;
    const std::vector<Eigen::Vector2f> stems = {{1.1f, 1.0f}, {3.0f, 3.0f}, {3.0f, 1.0f}};
    const auto trees = collect_trees(t.tile.cloud, terrain, ids, 3, stems, {0.2f, 0.05f, 0.3f}, 2.0f);
    ASSERT_EQ(trees.size(), 2u);
    EXPECT_FLOAT_EQ(trees[0].base.x(), 1.1f);
    EXPECT_FLOAT_EQ(trees[0].stem_radius, 0.2f);
    EXPECT_FLOAT_EQ(trees[1].base.x(), 3.0f);
    EXPECT_FLOAT_EQ(trees[1].base.y(), 1.0f);
    EXPECT_FLOAT_EQ(trees[1].stem_radius, 0.3f);
}

}  // namespace
