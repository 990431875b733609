// Forest tiles: placement without trunk overlap, truth table, ground.
#include "config/species_profile.hpp"
#include "core/error.hpp"
#include "support/species_profiles.hpp"
#include "synth/tile.hpp"

#include <gtest/gtest.h>

#include <sstream>

using namespace treelobes;
using treelobes::test::species_profiles;

namespace {

synth::TileOptions small_tile() {
    synth::TileOptions t;
    t.trees = 25;
    t.size_m = 40;
    t.grow.max_leaves = 2000;
    return t;
}

// Radius of the trunk at the root collar (widest level-0 node below 0.5 m).
double collar(const synth::SyntheticTree& tree) {
    double r = 0;
    for (std::size_t i = 0; i < tree.skeleton.size(); ++i)
        if (tree.node_level[i] == 0 && tree.skeleton.nodes[i].position.z() < 0.5f)
            r = std::max(r, tree.skeleton.nodes[i].position.head<2>().norm() + static_cast<double>(tree.skeleton.nodes[i].radius));
    return r;
}

}  // namespace

TEST(Tile, TrunksNeverOverlapAndTruthMatches) {
    const synth::Tile tile = synth::make_tile(species_profiles(), 3, small_tile());
    ASSERT_EQ(tile.scene.trees.size(), 25u);
    ASSERT_EQ(tile.truth.size(), 25u);
    std::set<std::string> species;
    for (std::size_t i = 0; i < tile.scene.trees.size(); ++i) {
        const auto& a = tile.scene.trees[i];
        EXPECT_EQ(a.tree_id, static_cast<int>(i) + 1);
        EXPECT_EQ(tile.truth[i].tree_id, a.tree_id);
        EXPECT_EQ(tile.truth[i].species, a.tree.species);
        // Stem bases stand on the ground.
        EXPECT_NEAR(a.position.z(), tile.scene.ground->height(a.position.x(), a.position.y()), 1e-6);
        species.insert(a.tree.species);
        for (std::size_t j = 0; j < i; ++j) {
            const auto& b = tile.scene.trees[j];
            EXPECT_GT((a.position - b.position).head<2>().norm(), collar(a.tree) + collar(b.tree)) << i << " vs " << j;
        }
    }
    EXPECT_GT(species.size(), 5u);  // mixed species
    EXPECT_FALSE(tile.scene.understory.empty());
}

TEST(Tile, GroundSlopesAndIsRough) {
    synth::TileOptions t = small_tile();
    t.trees = 0;
    t.slope_deg = 10;
    const synth::Tile tile = synth::make_tile(species_profiles(), 8, t);
    const auto& g = *tile.scene.ground;
    const auto [lo, hi] = std::minmax_element(g.z.begin(), g.z.end());
    EXPECT_GT(*hi - *lo, 40 * std::tan(10 * 3.14159265 / 180) * 0.5);  // at least half the slope's relief
}

TEST(Tile, TruthCsvHasOneRowPerTree) {
    synth::TileOptions t = small_tile();
    t.trees = 4;
    t.species = {"pine", "oak"};
    t.origin = Eigen::Vector3d(600000, 5000000, 100);
    const synth::Tile tile = synth::make_tile(species_profiles(), 1, t);
    const std::string csv = synth::truth_csv(tile.truth);
    std::istringstream in(csv);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "tree_id,species,species_id,seed,x,y,z,height_m,dbh_m,crown_diameter_m,age_years");
    int rows = 0;
    while (std::getline(in, line)) {
        ++rows;
        EXPECT_TRUE(line.find(",pine,") != std::string::npos || line.find(",oak,") != std::string::npos) << line;
        EXPECT_NE(line.find(",6000"), std::string::npos) << line;  // origin added
    }
    EXPECT_EQ(rows, 4);
}

TEST(Tile, OvercrowdedTilesFailWithAUsageError) {
    synth::TileOptions t = small_tile();
    t.trees = 200;
    t.size_m = 6;
    t.species = {"oak"};
    try {
        synth::make_tile(species_profiles(), 1, t);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::Usage);
        EXPECT_NE(std::string(e.what()).find("overlapping trunks"), std::string::npos);
    }
    t = small_tile();
    t.species = {"baobab"};
    EXPECT_THROW(synth::make_tile(species_profiles(), 1, t), Error);
}
