// Forest tiles: placement without trunk overlap, truth table, ground.
#include "config/species_profile.hpp"
#include "core/error.hpp"
#include "support/species_profiles.hpp"
#include "synth/tile.hpp"

#include <gtest/gtest.h>

#include <algorithm>
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

// Branch nodes of tree `a` that stand where `b` owns the canopy by the competition rule of
// synth/tile.hpp: nearer b's stem than a's relative to the crown radii, and below b's top.
int nodes_on_neighbour_ground(const synth::PlacedTree& a, double crown_a, const synth::PlacedTree& b, double crown_b, double top_b) {
    int count = 0;
    for (std::size_t n = 0; n < a.tree.skeleton.size(); ++n) {
        if (a.tree.node_level[n] == 0) continue;
        const Eigen::Vector3d p = a.position + a.tree.skeleton.nodes[n].position.cast<double>();
        const double own = (p - a.position).head<2>().norm() / crown_a;
        count += top_b > p.z() && (p - b.position).head<2>().norm() / crown_b < own;
    }
    return count;
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

// Two broad crowns 6 m apart: grown alone they interpenetrate; with competition neither keeps a
// branch on the other's ground, both keep their trunks, and the truth is measured on the cut trees.
TEST(Tile, CompetingCrownsDoNotInterpenetrate) {
    synth::TileOptions t = small_tile();
    t.trees = 2;
    t.size_m = 12;
    t.spacing = 0;
    t.understory_per_100m2 = 0;
    t.species = {"oak"};
    const synth::Tile alone = synth::make_tile(species_profiles(), 5, t);
    t.competition = true;
    const synth::Tile competing = synth::make_tile(species_profiles(), 5, t);
    ASSERT_EQ(competing.scene.trees.size(), 2u);

    const auto top = [](const synth::PlacedTree& p) { return p.position.z() + synth::measure(p.tree).height_m; };
    const auto crown = [](const synth::PlacedTree& p) { return 0.5 * synth::measure(p.tree).crown_diameter_m; };
    const auto& a0 = alone.scene.trees[0];
    const auto& b0 = alone.scene.trees[1];
    const double crown_a = crown(a0), crown_b = crown(b0);
    EXPECT_GT(nodes_on_neighbour_ground(a0, crown_a, b0, crown_b, top(b0)) + nodes_on_neighbour_ground(b0, crown_b, a0, crown_a, top(a0)),
              20);

    const auto& a = competing.scene.trees[0];
    const auto& b = competing.scene.trees[1];
    EXPECT_EQ(a.position, a0.position);  // the same stand, only the crowns differ
    EXPECT_EQ(nodes_on_neighbour_ground(a, crown_a, b, crown_b, top(b0)), 0);
    EXPECT_EQ(nodes_on_neighbour_ground(b, crown_b, a, crown_a, top(a0)), 0);
    for (std::size_t i = 0; i < 2; ++i) {
        const auto& cut = competing.scene.trees[i].tree;
        const auto& whole = alone.scene.trees[i].tree;
        EXPECT_LT(cut.skeleton.size(), whole.skeleton.size());
        EXPECT_LT(cut.leaves.size(), whole.leaves.size());
        EXPECT_NO_THROW(cut.skeleton.validate("competing tree"));
        const auto trunk = [](const synth::SyntheticTree& tree) { return std::count(tree.node_level.begin(), tree.node_level.end(), 0); };
        EXPECT_EQ(trunk(cut), trunk(whole));
        for (const auto& leaf : cut.leaves) EXPECT_LT(static_cast<std::size_t>(leaf.internode), cut.skeleton.size());
        EXPECT_DOUBLE_EQ(competing.truth[i].crown_diameter_m, synth::measure(cut).crown_diameter_m);
        EXPECT_LE(competing.truth[i].crown_diameter_m, alone.truth[i].crown_diameter_m);
    }
}
