// synth::grow: valid skeletons, determinism, natural variation, species character, leaf budget.
#include "config/species_profile.hpp"
#include "core/error.hpp"
#include "support/species_profiles.hpp"
#include "synth/grow.hpp"
#include "synth/tree_mesh.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace treelobes;
using treelobes::test::species_profiles;

namespace {

const SpeciesProfile& species(const std::string& name) { return find_species_profile(species_profiles(), name); }

synth::GrowOptions small_budget() {
    synth::GrowOptions o;
    o.max_leaves = 20000;
    return o;
}

// Fraction of last-level internodes that point downward (weeping habit).
double drooping_fraction(const synth::SyntheticTree& tree) {
    const int last = *std::max_element(tree.node_level.begin(), tree.node_level.end());
    int down = 0, total = 0;
    for (std::size_t i = 1; i < tree.skeleton.size(); ++i) {
        if (tree.node_level[i] != last) continue;
        const auto& n = tree.skeleton.nodes[i];
        down += n.position.z() < tree.skeleton.nodes[n.parent].position.z() ? 1 : 0;
        ++total;
    }
    return total ? static_cast<double>(down) / total : 0.0;
}

}  // namespace

TEST(Grow, EverySpeciesGivesAValidTreeWithinItsRanges) {
    for (const auto& p : species_profiles()) {
        const synth::SyntheticTree tree = synth::grow(p, 7, small_budget());
        SCOPED_TRACE(p.entry.name);
        EXPECT_NO_THROW(tree.skeleton.validate(p.entry.name));
        ASSERT_EQ(tree.node_level.size(), tree.skeleton.size());
        ASSERT_EQ(tree.internode_start_radius.size(), tree.skeleton.size());
        EXPECT_EQ(tree.species_id, p.entry.id);
        const synth::TreeMetrics m = synth::measure(tree);
        // The height lands on the drawn value within leaves' overshoot.
        EXPECT_GE(m.height_m, 0.9 * p.variation.height_m.min);
        EXPECT_LE(m.height_m, 1.1 * p.variation.height_m.max);
        EXPECT_GE(m.dbh_m, 0.7 * p.variation.dbh_m.min);
        EXPECT_LE(m.dbh_m, 1.3 * p.variation.dbh_m.max);
        EXPECT_GT(m.leaves, 1000u);
        EXPECT_LE(m.leaves, 20000u * 1.05);
        for (const auto& leaf : tree.leaves) {
            ASSERT_GE(leaf.internode, 1);
            ASSERT_LT(leaf.internode, static_cast<int>(tree.skeleton.size()));
        }
        for (const auto& node : tree.skeleton.nodes) {
            ASSERT_GT(node.radius, 0.0f);
            ASSERT_GT(node.position.z(), -1e-3f);  // nothing grows into the ground
        }
    }
}

TEST(Grow, MainChildContinuesTheStem) {
    const synth::SyntheticTree tree = synth::grow(species("oak"), 3, small_budget());
    int checked = 0;
    for (std::size_t i = 0; i < tree.skeleton.size(); ++i) {
        const auto& children = tree.skeleton.nodes[i].children;
        const bool continues =
                std::any_of(children.begin(), children.end(), [&](int c) { return tree.node_level[c] == tree.node_level[i]; });
        if (children.size() < 2 || !continues) continue;
        EXPECT_EQ(tree.node_level[children[0]], tree.node_level[i]) << "node " << i;
        ++checked;
    }
    EXPECT_GT(checked, 100);
}

TEST(Grow, SameSeedSameTreeOtherSeedOtherTree) {
    const auto a = synth::grow(species("birch"), 11, small_budget());
    const auto b = synth::grow(species("birch"), 11, small_budget());
    const auto c = synth::grow(species("birch"), 12, small_budget());
    ASSERT_EQ(a.skeleton.size(), b.skeleton.size());
    for (std::size_t i = 0; i < a.skeleton.size(); ++i) {
        ASSERT_EQ(a.skeleton.nodes[i].position, b.skeleton.nodes[i].position);
        ASSERT_EQ(a.skeleton.nodes[i].radius, b.skeleton.nodes[i].radius);
    }
    ASSERT_EQ(a.leaves.size(), b.leaves.size());
    EXPECT_NE(synth::measure(a).height_m, synth::measure(c).height_m);
}

TEST(Grow, IndividualsVaryLikeRealTrees) {
    std::vector<double> heights, crowns;
    for (int seed = 1; seed <= 12; ++seed) {
        const auto m = synth::measure(synth::grow(species("pine"), seed, small_budget()));
        heights.push_back(m.height_m);
        crowns.push_back(m.crown_diameter_m);
    }
    const auto [hlo, hhi] = std::minmax_element(heights.begin(), heights.end());
    const auto [clo, chi] = std::minmax_element(crowns.begin(), crowns.end());
    EXPECT_GT(*hhi - *hlo, 5.0);  // the 12-28 m range is used
    EXPECT_GT(*chi / *clo, 1.3);  // crowns differ too
}

TEST(Grow, SpeciesLookDifferent) {
    const auto willow = synth::grow(species("willow"), 5, small_budget());
    const auto pine = synth::grow(species("pine"), 5, small_budget());
    EXPECT_GT(drooping_fraction(willow), 0.6);
    EXPECT_LT(drooping_fraction(pine), drooping_fraction(willow) - 0.2);

    // The palm's trunk is bare up to its crown of fronds.
    const auto palm = synth::grow(species("palm"), 5, small_budget());
    const double height = synth::measure(palm).height_m;
    for (std::size_t i = 1; i < palm.skeleton.size(); ++i)
        if (palm.node_level[i] == 1) {
            const int parent = palm.skeleton.nodes[i].parent;
            if (palm.node_level[parent] == 0) {
                EXPECT_GT(palm.skeleton.nodes[parent].position.z(), 0.6 * height);
            }
        }
    // Delonix crowns are wider than tall, pines much taller than wide.
    const auto delonix = synth::measure(synth::grow(species("delonix"), 5, small_budget()));
    EXPECT_GT(delonix.crown_diameter_m, 0.8 * delonix.height_m);
    const auto pm = synth::measure(pine);
    EXPECT_LT(pm.crown_diameter_m, 0.7 * pm.height_m);
}

TEST(Grow, LeafDensityKeepsLeafArea) {
    synth::GrowOptions full, sparse;  // the default budget holds this tree's leaves
    sparse.leaf_density = 0.25;
    const auto a = synth::measure(synth::grow(species("bischofia_polycarpa"), 2, full));
    const auto b = synth::measure(synth::grow(species("bischofia_polycarpa"), 2, sparse));
    EXPECT_NEAR(static_cast<double>(b.leaves) / a.leaves, 0.25, 0.05);
    EXPECT_NEAR(b.leaf_area_m2 / a.leaf_area_m2, 1.0, 0.15);
    // The budget caps the count and keeps the area.
    synth::GrowOptions capped;
    capped.max_leaves = 10000;
    const auto c = synth::measure(synth::grow(species("bischofia_polycarpa"), 2, capped));
    EXPECT_LE(c.leaves, 10500u);
    EXPECT_NEAR(c.leaf_area_m2 / a.leaf_area_m2, 1.0, 0.15);
    // And the species' LAI is met.
    EXPECT_NEAR(a.lai, species("bischofia_polycarpa").growth.leaves.lai, 1.0);
}

TEST(Grow, WinterTreesHaveNoLeaves) {
    synth::GrowOptions o = small_budget();
    o.leaves = false;
    EXPECT_TRUE(synth::grow(species("oak"), 1, o).leaves.empty());
}

TEST(Grow, BadOptionsAreUsageErrors) {
    synth::GrowOptions o;
    o.height_m = -1;
    EXPECT_THROW(synth::grow(species("oak"), 1, o), Error);
    o = {};
    o.leaf_density = 0;
    EXPECT_THROW(synth::grow(species("oak"), 1, o), Error);
    o = {};
    o.max_internode_m = 0;
    try {
        synth::grow(species("oak"), 1, o);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::Usage);
    }
}

TEST(Grow, RunawayProfilesFailInsteadOfExhaustingMemory) {
    SpeciesProfile p = species("oak");
    for (auto& level : p.growth.levels) level.branches = 200;
    EXPECT_THROW(synth::grow(p, 1), Error);
}

TEST(TreeMesh, BranchesAndLeaves) {
    const auto tree = synth::grow(species("lagerstroemia"), 1, small_budget());
    const synth::TreeMesh mesh = synth::tree_mesh(tree);
    EXPECT_GT(mesh.wood.face_count(), tree.skeleton.size());
    EXPECT_EQ(mesh.leaves.face_count(), 2 * tree.leaves.size());
    EXPECT_EQ(mesh.combined().face_count(), mesh.wood.face_count() + mesh.leaves.face_count());
    // Leaf area of the mesh equals the measured leaf area.
    EXPECT_NEAR(mesh.leaves.area(), synth::measure(tree).leaf_area_m2, 1e-3 * synth::measure(tree).leaf_area_m2);
}

namespace {

// Radius of the trunk (level 0) at the node nearest to height z.
double trunk_radius_at(const synth::SyntheticTree& tree, double z) {
    double best = 1e9, radius = 0;
    for (std::size_t i = 0; i < tree.skeleton.size(); ++i) {
        if (tree.node_level[i] != 0) continue;
        const double d = std::abs(tree.skeleton.nodes[i].position.z() - z);
        if (d < best) best = d, radius = tree.skeleton.nodes[i].radius;
    }
    return radius;
}

// Height below which `fraction` of the leaves sit.
double leaf_quantile(const synth::SyntheticTree& tree, double fraction) {
    std::vector<float> z;
    for (const auto& leaf : tree.leaves) z.push_back(leaf.base.z());
    std::sort(z.begin(), z.end());
    return z.empty() ? 0.0 : z[static_cast<std::size_t>(fraction * static_cast<double>(z.size() - 1))];
}

}  // namespace

TEST(Grow, ParaboloidBoleIsFullerThanACone) {
    SpeciesProfile cone = species("pine");
    cone.growth.levels[0].taper_power = 1.0;
    SpeciesProfile paraboloid = cone;
    paraboloid.growth.levels[0].taper_power = 0.5;
    synth::GrowOptions o = small_budget();
    o.height_m = 20;
    const auto a = synth::grow(cone, 4, o), b = synth::grow(paraboloid, 4, o);
    // Same DBH (the radius is calibrated at 1.3 m), but a fuller stem higher up.
    EXPECT_NEAR(synth::measure(a).dbh_m, synth::measure(b).dbh_m, 0.1 * synth::measure(a).dbh_m);
    EXPECT_GT(trunk_radius_at(b, 10.0), 1.15 * trunk_radius_at(a, 10.0));
}

TEST(Grow, DeadLowerCrownKeepsBareBranches) {
    SpeciesProfile alive = species("oak");
    alive.growth.dead_crown = 0.0;
    SpeciesProfile pruned = alive;
    pruned.growth.dead_crown = 0.5;
    const auto a = synth::grow(alive, 6, small_budget()), b = synth::grow(pruned, 6, small_budget());
    // Same branching above the dead zone, no foliage in it: the lowest leaves sit higher ...
    EXPECT_GT(leaf_quantile(b, 0.05), leaf_quantile(a, 0.05) + 1.0);
    // ... while first-order branches still leave the trunk below them.
    const double lowest_leaf = leaf_quantile(b, 0.0);
    bool bare_branch = false;
    for (std::size_t i = 1; i < b.skeleton.size() && !bare_branch; ++i)
        bare_branch =
                b.node_level[i] == 1 && b.node_level[b.skeleton.nodes[i].parent] == 0 && b.skeleton.nodes[i].position.z() < lowest_leaf;
    EXPECT_TRUE(bare_branch);
}

// Cutting a node takes its whole subtree and the leaves on it, and leaves a valid tree whose
// remaining nodes, levels and leaves are those of the original.
TEST(Grow, PruningASubtreeKeepsTheRestIntact) {
    const synth::SyntheticTree whole = synth::grow(species("birch"), 4, small_budget());
    // The first first-order branch, and every node that grows from it.
    int branch = -1;
    for (std::size_t i = 0; i < whole.skeleton.size() && branch < 0; ++i)
        if (whole.node_level[i] == 1) branch = static_cast<int>(i);
    ASSERT_GT(branch, 0);
    std::vector<bool> below(whole.skeleton.size(), false);
    below[static_cast<std::size_t>(branch)] = true;
    for (std::size_t i = 1; i < whole.skeleton.size(); ++i)
        if (below[static_cast<std::size_t>(whole.skeleton.nodes[i].parent)]) below[i] = true;
    const auto subtree = static_cast<std::size_t>(std::count(below.begin(), below.end(), true));
    std::size_t leaves_on_it = 0;
    for (const auto& leaf : whole.leaves) leaves_on_it += below[static_cast<std::size_t>(leaf.internode)];
    ASSERT_GT(subtree, 1u);
    ASSERT_GT(leaves_on_it, 0u);

    synth::SyntheticTree cut = whole;
    synth::prune_subtrees(cut, [&](int node) { return node == branch; });
    EXPECT_NO_THROW(cut.skeleton.validate("pruned tree"));
    ASSERT_EQ(cut.skeleton.size(), whole.skeleton.size() - subtree);
    ASSERT_EQ(cut.node_level.size(), cut.skeleton.size());
    ASSERT_EQ(cut.internode_start_radius.size(), cut.skeleton.size());
    ASSERT_EQ(cut.leaves.size(), whole.leaves.size() - leaves_on_it);
    // The survivors in their old order: positions, levels and the leaves' internodes map across.
    std::size_t k = 0;
    for (std::size_t i = 0; i < whole.skeleton.size(); ++i) {
        if (below[i]) continue;
        EXPECT_EQ(cut.skeleton.nodes[k].position, whole.skeleton.nodes[i].position);
        EXPECT_EQ(cut.node_level[k], whole.node_level[i]);
        ++k;
    }
    for (const auto& leaf : cut.leaves) EXPECT_LT(static_cast<std::size_t>(leaf.internode), cut.skeleton.size());

    synth::SyntheticTree untouched = whole;
    synth::prune_subtrees(untouched, [](int) { return false; });
    EXPECT_EQ(untouched.skeleton.size(), whole.skeleton.size());
    synth::SyntheticTree root_only = whole;
    synth::prune_subtrees(root_only, [](int) { return true; });
    EXPECT_EQ(root_only.skeleton.size(), 1u);  // the root never goes
    EXPECT_TRUE(root_only.leaves.empty());
}
