// Tree segmentation on toy tiles: two airborne crowns, two terrestrial stems sharing a crown
// space (multi-source Dijkstra), points of classes that are no tree's, the automatic mode, and
// the degenerate tiles.
#include "segment/segment_trees.hpp"

#include "core/error.hpp"
#include "segment/segmentation_score.hpp"
#include "support/test_support.hpp"
#include "toy_tiles.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <map>
#include <numbers>

using namespace treelobes;
using test::ToyTile;

namespace {

// Ground 20 x 12 m at 0.3 m spacing (about 11 returns per m^2, some reaching the ground
// under the crowns) with two conical crowns.
ToyTile two_crowns_airborne() {
    ToyTile tile;
    test::add_ground(tile, 0, 20, 0, 12, 0.3f, 5.0f, 0.1f, [](float x, float) { return static_cast<int>(x * 10) % 2; });
    test::add_cone_crown(tile, 5, 6, 15, 3, 0.3f, 5.0f, 0.1f, 1);
    test::add_cone_crown(tile, 12.5f, 6, 12, 3, 0.3f, 5.0f, 0.1f, 2);
    return tile;
}

// Two stems 3 m apart whose ball crowns overlap by 2 m, a bush 4 m from both, dense ground.
ToyTile two_stems_terrestrial() {
    ToyTile tile = test::flat_ground(-4, 7, -4, 6);
    test::add_stem_and_ball(tile, 0, 0, 0.15f, 8, 2.5f, 0.15f, 1);
    test::add_stem_and_ball(tile, 3, 0, 0.12f, 8, 2.5f, 0.15f, 2);
    for (float z = 0.35f; z <= 1.0f; z += 0.05f)
        for (float y = 3.6f; y <= 4.4f; y += 0.05f)
            for (float x = 1.1f; x <= 1.9f; x += 0.05f) tile.add({x, y, z}, 0);
    test::classify_flat_ground(tile);
    return tile;
}

// Share of each true tree's points carrying the id found most often among them, and that id.
std::map<std::int32_t, std::pair<std::int32_t, double>> dominant_ids(const ToyTile& tile, const TreeSegmentation& result) {
    std::map<std::int32_t, std::map<std::int32_t, std::size_t>> counts;
    for (std::size_t i = 0; i < tile.truth.size(); ++i)
        if (tile.truth[i]) ++counts[tile.truth[i]][result.tree_id[i]];
    std::map<std::int32_t, std::pair<std::int32_t, double>> dominant;
    for (const auto& [truth, ids] : counts) {
        std::size_t total = 0, best = 0;
        std::int32_t best_id = 0;
        for (const auto& [id, n] : ids) {
            total += n;
            if (n > best) {
                best = n;
                best_id = id;
            }
        }
        dominant[truth] = {best_id, static_cast<double>(best) / static_cast<double>(total)};
    }
    return dominant;
}

}  // namespace

TEST(SegmentTrees, AirborneSeparatesTwoCrownsHighestFirst) {
    const ToyTile tile = two_crowns_airborne();
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    SegmentOptions options;
    options.mode = ScanMode::Airborne;
    const TreeSegmentation result = segment_trees(tile.cloud, terrain, options);
    ASSERT_EQ(result.trees.size(), 2u);
    EXPECT_EQ(result.mode_used, ScanMode::Airborne);
    const auto dominant = dominant_ids(tile, result);
    EXPECT_EQ(dominant.at(1).first, 1);  // the higher tree is found first
    EXPECT_EQ(dominant.at(2).first, 2);
    EXPECT_EQ(dominant.at(1).second, 1.0);  // every crown and stem point, none lost
    EXPECT_EQ(dominant.at(2).second, 1.0);
    EXPECT_NEAR(result.trees[0].top.x(), 5.0f, 0.2f);
    EXPECT_NEAR(result.trees[0].top.z() - result.trees[0].base.z(), 15.0f, 0.2f);
    EXPECT_NEAR(result.trees[1].top.x(), 12.5f, 0.2f);
    for (std::size_t i = 0; i < tile.truth.size(); ++i)
        if (!tile.truth[i]) {
            ASSERT_EQ(result.tree_id[i], 0) << "ground point " << i;
        }
}

// A classified survey marks buildings, wires and water, and their points are no tree's: a flat
// roof 6 m up, 6 x 4 m, beside the crowns of two_crowns_airborne.
TEST(SegmentTrees, PointsOfClassesThatAreNoTreesAreLeftOut) {
    ToyTile tile = two_crowns_airborne();
    const std::size_t roof_begin = tile.cloud.size();
    for (float y = 1.0f; y <= 5.0f; y += 0.3f)
        for (float x = 13.0f; x <= 19.0f; x += 0.3f) tile.add({x, y + 6.0f, test::ground_height(x, y + 6.0f, 5.0f, 0.1f) + 6.0f}, 0);
    test::classify_ground(tile);  // the roof too is "ground" here; it gets its own class below
    SegmentOptions options;
    options.mode = ScanMode::Airborne;
    for (std::uint8_t roof_class : {std::uint8_t{6}, std::uint8_t{1}}) {
        for (std::size_t i = roof_begin; i < tile.cloud.size(); ++i) tile.cloud.classification[i] = roof_class;
        const TreeSegmentation result = segment_trees(tile.cloud, analyse_terrain(tile.cloud, {}), options);
        std::size_t roof_in_trees = 0;
        for (std::size_t i = roof_begin; i < tile.cloud.size(); ++i) roof_in_trees += result.tree_id[i] != 0;
        if (roof_class == 6) {  // a building
            EXPECT_EQ(result.trees.size(), 2u);
            EXPECT_EQ(roof_in_trees, 0u);
        } else {  // unclassified: nothing tells the roof from a crown
            EXPECT_GT(roof_in_trees, 0u);
        }
    }
}

// The tops are found on the smoothed CHM, and a crown whose highest returns ring a lower centre
// (a palm's fronds, a dip between leaf clumps) has its smoothed maximum over that centre. Its
// crown must still grow over the higher cells around it: measured against the centre cell's own
// height they were refused, and the tree kept one cell of its crown.
TEST(SegmentTrees, AirborneCrownGrowsPastTheHigherCellsAroundASmoothedTop) {
    ToyTile tile;
    test::add_ground(tile, 0, 12, 0, 12, 0.3f, 0.0f, 0.0f, [](float, float) { return false; });
    const float centre = 6.25f;  // the centre of a 0.5 m CHM cell: its highest return is the dip's
    for (float y = 2.0f; y <= 10.0f; y += 0.2f)
        for (float x = 2.0f; x <= 10.0f; x += 0.2f) {
            const float r = std::hypot(x - centre, y - centre);
            if (r <= 4.0f) tile.add({x, y, r < 0.4f ? 11.5f : 12.0f - 0.25f * r * r}, 1);
        }
    test::classify_ground(tile);
    SegmentOptions options;
    options.mode = ScanMode::Airborne;
    const TreeSegmentation result = segment_trees(tile.cloud, analyse_terrain(tile.cloud, {}), options);
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_GT(dominant_ids(tile, result).at(1).second, 0.95);
    EXPECT_NEAR(result.trees[0].top.z(), 12.0f, 0.1f);
}

namespace {

// Flat classified ground over [0, width] x [0, depth] and dome-shaped crowns (x, y, height; ids
// 1, 2, ...) as an airborne survey sees them: a return every `step` metres, moved at random by up
// to +-jitter/2 across and by up to `noise` down (a fixed sequence from `seed`).
struct DomeScan {
    float step, jitter, radius, curvature, noise;
    std::uint32_t seed;
};

ToyTile sparse_domes(const DomeScan& scan, float width, float depth, std::initializer_list<Eigen::Vector3f> domes) {
    ToyTile tile;
    std::uint32_t state = scan.seed;
    const auto uniform = [&state] {  // a fixed linear congruential sequence in [0, 1)
        state = state * 1664525u + 1013904223u;
        return static_cast<float>(state >> 8) / static_cast<float>(1u << 24);
    };
    const auto jittered = [&](float v) { return v + scan.jitter * (uniform() - 0.5f); };
    for (float y = 0.0f; y <= depth; y += scan.step)
        for (float x = 0.0f; x <= width; x += scan.step) {
            const float px = jittered(x), py = jittered(y);
            tile.add({px, py, 0.0f}, 0);
        }
    std::int32_t id = 0;
    for (const Eigen::Vector3f& dome : domes) {
        ++id;
        for (float y = dome.y() - scan.radius; y <= dome.y() + scan.radius; y += scan.step)
            for (float x = dome.x() - scan.radius; x <= dome.x() + scan.radius; x += scan.step) {
                const float px = jittered(x), py = jittered(y);
                const float r = std::hypot(px - dome.x(), py - dome.y());
                if (r <= scan.radius) tile.add({px, py, dome.z() - scan.curvature * r * r - scan.noise * uniform()}, id);
            }
    }
    test::classify_ground(tile);
    return tile;
}

}  // namespace

// A survey of 1 return per m^2 (a national programme's density) over two broad, bumpy crowns:
// returns 1 m apart on a jittered grid, each 0-0.6 m below its crown's dome. Drawn as 0.15 m discs
// on 0.5 m cells, most CHM cells stay empty and a crown grown from its top cannot cross them:
// 95 % of each crown's points stay in no tree (on the bench's sparse tiles the tops fell apart
// too). With the cell and discs grown to the returns' spacing the CHM is whole and each crown one
// tree.
TEST(SegmentTrees, ASparseSurveyKeepsEachCrownWhole) {
    ToyTile tile = sparse_domes({.step = 1.0f, .jitter = 0.8f, .radius = 6.0f, .curvature = 0.15f, .noise = 0.6f, .seed = 12345u}, 30.0f,
                                16.0f, {{8.0f, 8.0f, 15.0f}, {21.0f, 8.0f, 12.0f}});
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    SegmentOptions options;
    options.mode = ScanMode::Airborne;
    const TreeSegmentation result = segment_trees(tile.cloud, terrain, options);
    EXPECT_NEAR(result.return_spacing, 1.0f, 0.15f);
    EXPECT_NEAR(result.chm_point_radius, 0.7071f * result.return_spacing, 1e-4f);
    EXPECT_NEAR(result.chm_cell, 0.75f * result.return_spacing, 1e-4f);
    ASSERT_EQ(result.trees.size(), 2u);
    const auto dominant = dominant_ids(tile, result);
    EXPECT_EQ(dominant.at(1).first, 1);
    EXPECT_EQ(dominant.at(2).first, 2);
    EXPECT_GT(dominant.at(1).second, 0.95);
    EXPECT_GT(dominant.at(2).second, 0.95);

    options.cell_per_spacing = options.disc_per_spacing = 0.0f;  // the fixed 0.5 m cells and 0.15 m discs
    const TreeSegmentation fixed = segment_trees(tile.cloud, terrain, options);
    EXPECT_EQ(fixed.chm_cell, 0.5f);
    const auto fixed_dominant = dominant_ids(tile, fixed);
    EXPECT_EQ(fixed_dominant.at(1).first, 0);  // most of each crown in no tree
    EXPECT_EQ(fixed_dominant.at(2).first, 0);
}

// Below about 0.5 pulses per m^2 the spacing reads short (2 m cells that mostly hold one return
// cannot show more than 2 m), and discs of s/sqrt(2) leave a crown in pieces: there the discs take
// the whole spacing (on synthetic stands at 0.1-0.35 pulses per m^2 F1 rose from 0.25-0.78 to
// 0.58-0.82, docs/segment.md). Two domes of 7 m radius, a return every 2.6 m (0.15 per m^2).
TEST(SegmentTrees, ASparserSurveyDrawsDiscsOfTheWholeSpacing) {
    ToyTile tile = sparse_domes({.step = 2.6f, .jitter = 1.0f, .radius = 7.0f, .curvature = 0.12f, .noise = 0.5f, .seed = 777u}, 36.0f,
                                20.0f, {{9.0f, 10.0f, 16.0f}, {27.0f, 10.0f, 14.0f}});
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    SegmentOptions options;
    options.mode = ScanMode::Airborne;
    const TreeSegmentation sparse = segment_trees(tile.cloud, terrain, options);
    ASSERT_GT(sparse.return_spacing, kSparseSurveyReturnSpacing);
    EXPECT_NEAR(sparse.chm_point_radius, 1.0f * sparse.return_spacing, 1e-4f);
    EXPECT_NEAR(sparse.chm_cell, 0.75f * sparse.return_spacing, 1e-4f);
    const auto whole = dominant_ids(tile, sparse);
    EXPECT_EQ(whole.at(1).first, 1);
    EXPECT_EQ(whole.at(2).first, 2);

    options.sparse_disc_per_spacing = options.disc_per_spacing;  // as a denser survey would draw them
    const TreeSegmentation narrow = segment_trees(tile.cloud, terrain, options);
    EXPECT_NEAR(narrow.chm_point_radius, 0.7071f * narrow.return_spacing, 1e-4f);
    options.disc_per_spacing = options.cell_per_spacing = 0.0f;  // the fixed grid stays fixed
    EXPECT_EQ(segment_trees(tile.cloud, terrain, options).chm_point_radius, options.point_radius);
}

// Pulses per m^2, as surveys are ordered: first returns over the footprint. A pulse through a
// crown gives several returns in one place, so the returns' spacing reads 1.7 m in every survey
// of 0.025-0.1 pulses per m^2; the pulse density does not saturate.
TEST(SegmentTrees, SurveyPulseDensityCountsPulsesNotReturns) {
    const auto survey = [](float step, float width, int returns) {
        PointCloud cloud;
        for (float y = 0.5f * step; y < width; y += step)
            for (float x = 0.5f * step; x < width; x += step)
                for (int r = 1; r <= returns; ++r) {
                    cloud.positions.emplace_back(x, y, 10.0f - 3.0f * static_cast<float>(r));
                    cloud.return_number.push_back(static_cast<std::uint8_t>(r));
                }
        return cloud;
    };
    PointCloud sparse = survey(std::sqrt(10.0f), 100.0f, 3);  // 0.1 pulses per m^2, three returns each
    EXPECT_NEAR(survey_pulse_density(sparse), 0.1f, 0.015f);
    sparse.return_number.clear();  // without return numbers every point counts
    EXPECT_NEAR(survey_pulse_density(sparse), 0.3f, 0.045f);
    EXPECT_NEAR(survey_pulse_density(survey(1.0f / 3.0f, 12.0f, 2)), 9.0f, 0.6f);  // a clip of one crown, within 10 m cells
    EXPECT_NEAR(survey_pulse_density(survey(100.0f, 1000.0f, 1)), 1e-4f, 3e-5f);   // one pulse per hectare, one per cell
    EXPECT_EQ(survey_pulse_density(PointCloud{}), 0.0f);
}

// Top merging by prominence that grows with the top's height (2 m up to a 17 m top, 0.12 x the
// height above). Two 12 m cones with tops 7.6 m apart, which on the smoothed CHM rise more than
// 2 m but less than 3 m above their pass, are two trees; a fixed 3 m joins them. Two bumps 8 m
// apart on a 30 m dome, which rise more than 3 m but less than 0.12 x their height above their
// saddle, are one crown; a fixed 3 m splits it.
TEST(SegmentTrees, TopProminenceGrowsWithTheTopsHeight) {
    const auto surface_tile = [](auto height_at) {
        ToyTile tile;
        for (float y = 0.0f; y <= 30.0f; y += 0.25f)
            for (float x = 0.0f; x <= 40.0f; x += 0.25f) {
                const float h = height_at(x, y);
                tile.add({x, y, h > 0.5f ? h : 0.0f}, h > 0.5f ? 1 : 0);
            }
        test::classify_ground(tile);
        return tile;
    };
    // Trees found with the defaults, or with a fixed prominence of 3 m (the setting before).
    const auto tree_count = [](const ToyTile& tile, bool fixed_prominence) {
        SegmentOptions options;
        options.mode = ScanMode::Airborne;
        if (fixed_prominence) {
            options.min_top_prominence = 3.0f;
            options.top_prominence_ratio = 0.0f;
        }
        return segment_trees(tile.cloud, analyse_terrain(tile.cloud, {}), options).trees.size();
    };
    const ToyTile small = surface_tile([](float x, float y) {
        const float a = 12.0f - std::hypot(x - 16.2f, y - 15.0f), b = 12.0f - std::hypot(x - 23.8f, y - 15.0f);
        return std::max({a, b, 0.0f}) > 5.0f ? std::max(a, b) : 0.0f;
    });
    EXPECT_EQ(tree_count(small, false), 2u);
    EXPECT_EQ(tree_count(small, true), 1u);
    const ToyTile broad = surface_tile([](float x, float y) {
        const float r = std::hypot(x - 20.0f, y - 15.0f);
        if (r > 12.0f) return 0.0f;
        const float bumps = 6.0f * std::max(std::exp(-std::pow(std::hypot(x - 16.0f, y - 15.0f) / 1.5f, 2.0f)),
                                            std::exp(-std::pow(std::hypot(x - 24.0f, y - 15.0f) / 1.5f, 2.0f)));
        return 26.0f - 0.08f * r * r + bumps;
    });
    EXPECT_EQ(tree_count(broad, false), 1u);
    EXPECT_EQ(tree_count(broad, true), 2u);
}

TEST(SegmentTrees, TerrestrialGrowsBothTreesFromTheirStemsInOneSearch) {
    const ToyTile tile = two_stems_terrestrial();
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    const TreeSegmentation result = segment_trees(tile.cloud, terrain, {});
    EXPECT_EQ(result.mode_used, ScanMode::Terrestrial) << result.mode_reason;
    ASSERT_EQ(result.trees.size(), 2u);
    EXPECT_NEAR(result.trees[0].base.x(), 0.0f, 0.02f);
    EXPECT_NEAR(result.trees[0].stem_radius, 0.15f, 0.01f);
    EXPECT_NEAR(result.trees[1].base.x(), 3.0f, 0.02f);
    EXPECT_NEAR(result.trees[1].stem_radius, 0.12f, 0.01f);
    const auto dominant = dominant_ids(tile, result);
    EXPECT_EQ(dominant.at(1).first, 1);
    EXPECT_EQ(dominant.at(2).first, 2);
    // The crowns overlap by 2 m: the shared lattice points go to one or the other.
    EXPECT_GT(dominant.at(1).second, 0.8);
    EXPECT_GT(dominant.at(2).second, 0.8);
    // Crown points on the far side of each ball belong to their own tree.
    for (std::size_t i = 0; i < tile.truth.size(); ++i) {
        const Eigen::Vector3f& p = tile.cloud.positions[i];
        if (p.z() > 6.0f && p.x() < -0.5f) {
            ASSERT_EQ(result.tree_id[i], 1);
        }
        if (p.z() > 6.0f && p.x() > 3.5f) {
            ASSERT_EQ(result.tree_id[i], 2);
        }
    }
    // The bush is out of reach (more than max_gap from any tree), the ground is not a tree.
    for (std::size_t i = 0; i < tile.truth.size(); ++i)
        if (!tile.truth[i]) {
            ASSERT_EQ(result.tree_id[i], 0) << "point " << i;
        }
    const SegmentationScore score = score_segmentation(tile.truth, result.tree_id, terrain.height_above_ground, 5.0f);
    EXPECT_EQ(score.f1, 1.0);
    EXPECT_GT(score.points_right, 0.85);
}

// Where a crown is seen through the gaps of others, its returns lie far apart (here 0.7 m). The
// graph's edges must span them, or the crown is left out as if beyond a gap: on the synthetic
// plots' far sides of crowns, 2-6 % of the tree points stayed 0 with edges of at most 0.5 m.
TEST(SegmentTrees, ASparselySeenCrownStaysWithItsTree) {
    ToyTile tile = test::flat_ground(-4, 4, -4, 4);
    for (float z = 0.0f; z <= 6.0f; z += 0.02f)
        for (int a = 0; a < 72; ++a) {
            const float t = static_cast<float>(a) * 5.0f * std::numbers::pi_v<float> / 180.0f;
            tile.add({0.15f * std::cos(t), 0.15f * std::sin(t), z}, 1);
        }
    for (float z = -2.1f; z <= 2.1f; z += 0.7f)
        for (float y = -2.1f; y <= 2.1f; y += 0.7f)
            for (float x = -2.1f; x <= 2.1f; x += 0.7f)
                if (x * x + y * y + z * z <= 2.1f * 2.1f) tile.add({x, y, 8.0f + z}, 1);
    test::classify_flat_ground(tile);
    const TreeSegmentation result = segment_trees(tile.cloud, analyse_terrain(tile.cloud, {}), {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].top.z(), 9.4f, 0.01f);  // the crown's highest lattice point
    for (std::size_t i = 0; i < tile.truth.size(); ++i)
        if (tile.cloud.positions[i].z() > 6.1f) {
            ASSERT_EQ(result.tree_id[i], 1) << "crown point " << i;
        }
}

// A treetop seen as a few clumps above a gap: the graph's edges do not reach them (each clump's
// nearest voxels are its own), so the paths leave them out; as pieces hanging in the air within
// attach_gap they join the tree, the upper clump through the lower one. A stray return and a
// bush on the ground beside the stem stay 0.
TEST(SegmentTrees, ADetachedTreetopJoinsItsTreeLinkByLink) {
    ToyTile tile = test::flat_ground(-4, 4, -4, 4);
    test::add_stem_and_ball(tile, 0, 0, 0.15f, 6, 2.0f, 0.15f, 1);  // crown top at 8 m
    const auto add_clump = [&tile](float x, float y, float z, std::int32_t id) {
        for (float dz = 0.0f; dz <= 0.3f; dz += 0.05f)
            for (float dy = 0.0f; dy <= 0.3f; dy += 0.05f)
                for (float dx = 0.0f; dx <= 0.3f; dx += 0.05f) tile.add({x + dx, y + dy, z + dz}, id);
    };
    add_clump(-0.15f, -0.15f, 9.5f, 1);   // 1.5 m above the crown
    add_clump(-0.15f, -0.15f, 11.3f, 1);  // 1.5 m above that, 3.3 m above the crown
    add_clump(1.5f, 1.5f, 0.4f, 0);       // a bush on the ground
    tile.add({1.8f, 0.0f, 9.3f}, 0);      // a stray return 1.5 m from the crown
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});

    const TreeSegmentation result = segment_trees(tile.cloud, terrain, {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].top.z(), 11.6f, 0.01f);
    for (std::size_t i = 0; i < tile.truth.size(); ++i)
        if (tile.cloud.positions[i].z() > 0.35f) {  // above the ground clearance
            ASSERT_EQ(result.tree_id[i], tile.truth[i]) << "point " << i;
        }

    SegmentOptions without;
    without.attach_gap = 0.0f;
    const TreeSegmentation paths_only = segment_trees(tile.cloud, terrain, without);
    ASSERT_EQ(paths_only.trees.size(), 1u);
    EXPECT_NEAR(paths_only.trees[0].top.z(), 7.9f, 0.01f);  // the crown's highest lattice point
}

// A broad trunk with a root flare (radius 1.1 m at the ground, 0.8 m at 1 m, 0.6 m from 2.5 m up:
// no single circle holds the slice 1-2 m above the ground) beside an ordinary stem.
TEST(SegmentTrees, ATaperingTrunkIsFoundLayerByLayer) {
    ToyTile tile = test::flat_ground(-4, 9, -4, 5);
    for (float z = 0.0f; z <= 8.0f; z += 0.02f) {
        const float radius = 0.6f + 0.5f * std::max(0.0f, 2.5f - z) / 2.5f;
        for (int a = 0; a < 144; ++a) {
            const float t = static_cast<float>(a) * 2.5f * std::numbers::pi_v<float> / 180.0f;
            tile.add({radius * std::cos(t), radius * std::sin(t), z}, 1);
        }
    }
    test::add_stem_and_ball(tile, 5, 0, 0.15f, 8, 2.0f, 0.15f, 2);
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});

    const TreeSegmentation result = segment_trees(tile.cloud, terrain, {});
    ASSERT_EQ(result.trees.size(), 2u);
    EXPECT_NEAR(result.trees[0].base.x(), 0.0f, 0.05f);
    EXPECT_NEAR(result.trees[0].base.y(), 0.0f, 0.05f);
    EXPECT_GT(result.trees[0].stem_radius, 0.65f);  // the layers' median, between 0.8 and 0.68 m
    EXPECT_LT(result.trees[0].stem_radius, 0.8f);
    EXPECT_NEAR(result.trees[1].stem_radius, 0.15f, 0.01f);

    SegmentOptions one_layer;  // one circle over the whole slice: the flared trunk is not a stem
    one_layer.stem_layer_height = 2.0f;
    const TreeSegmentation whole_slice = segment_trees(tile.cloud, terrain, one_layer);
    ASSERT_EQ(whole_slice.trees.size(), 1u);
    EXPECT_NEAR(whole_slice.trees[0].base.x(), 5.0f, 0.05f);
}

// A thick trunk (radius 0.5 m) on a skirt of roots 1.15 m wide up to 0.95 m above the ground, as
// the synthetic figs stand: nothing lies below the slice within 1.5 radii of its axis, but a
// trunk that thick may flare that far. A limb of 0.25 m hanging down to 1 m above the ground over
// a bush 0.6 m from its axis is no stem: a thin stem's foot is looked for within 1.5 radii.
TEST(SegmentTrees, AThickTrunkStandsOnItsButtresses) {
    ToyTile tile = test::flat_ground(-4, 9, -4, 4);
    const auto add_wall = [&](float cx, float radius, float z0, float z1, std::int32_t id) {
        for (float z = z0; z <= z1; z += 0.02f)
            for (int a = 0; a < 144; ++a) {
                const float t = static_cast<float>(a) * 2.5f * std::numbers::pi_v<float> / 180.0f;
                tile.add({cx + radius * std::cos(t), radius * std::sin(t), z}, id);
            }
    };
    add_wall(0.0f, 0.5f, 1.0f, 8.0f, 1);    // the trunk
    add_wall(0.0f, 1.15f, 0.0f, 0.95f, 1);  // its skirt of roots
    add_wall(5.0f, 0.25f, 1.0f, 3.5f, 2);   // the hanging limb
    add_wall(5.0f, 0.6f, 0.3f, 0.9f, 0);    // the bush under it
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});

    const TreeSegmentation result = segment_trees(tile.cloud, terrain, {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].base.x(), 0.0f, 0.05f);
    EXPECT_NEAR(result.trees[0].stem_radius, 0.5f, 0.02f);

    SegmentOptions no_buttresses;  // every stem's foot within 1.5 radii: the trunk is no stem
    no_buttresses.buttressed_stem_radius = 10.0f;
    EXPECT_TRUE(segment_trees(tile.cloud, terrain, no_buttresses).trees.empty());
    SegmentOptions every_stem_buttressed;  // the limb over the bush would pass for a stem
    every_stem_buttressed.buttressed_stem_radius = 0.0f;
    EXPECT_EQ(segment_trees(tile.cloud, terrain, every_stem_buttressed).trees.size(), 2u);
}

// A thick trunk (0.65 m) whose root flare reaches 1.7 m up the 1-2 m slice: below that, each layer
// shows the outer rim of its buttresses over half its circumference (1.35 m wide at 1 m, 0.95 m at
// 1.7 m) and six fins running in from the rim to the trunk, so that no circle holds half of a
// layer's points. Only the slice's top layers hold the trunk's circle: too few for a stem, unless
// the layers below are taken for what they are, the flare of that trunk (fine layers stand in for
// the many a slice cut on a slope holds).
TEST(SegmentTrees, AThickTrunkIsFoundAboveItsFlare) {
    ToyTile tile = test::flat_ground(-4, 4, -4, 4);
    constexpr float kTrunk = 0.65f;
    for (float z = 0.0f; z <= 6.0f; z += 0.02f) {
        if (z >= 1.7f) {
            for (int a = 0; a < 144; ++a) {
                const float t = static_cast<float>(a) * 2.5f * std::numbers::pi_v<float> / 180.0f;
                tile.add({kTrunk * std::cos(t), kTrunk * std::sin(t), z}, 1);
            }
            continue;
        }
        const float rim = 1.35f - 0.4f * std::max(0.0f, z - 1.0f) / 0.7f - 0.1f * std::max(0.0f, 1.0f - z);
        for (int a = 0; a < 144; a += 2) {  // the buttresses' outer edges, half the circumference
            const float t = static_cast<float>(a) * 2.5f * std::numbers::pi_v<float> / 180.0f;
            tile.add({rim * std::cos(t), rim * std::sin(t), z}, 1);
        }
        for (int fin = 0; fin < 6; ++fin) {
            const float t = static_cast<float>(fin) * std::numbers::pi_v<float> / 3.0f + 0.1f;
            for (float r = kTrunk; r < rim; r += 0.02f) tile.add({r * std::cos(t), r * std::sin(t), z}, 1);
        }
    }
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    SegmentOptions fine_layers;
    fine_layers.stem_layer_height = 0.125f;

    const TreeSegmentation result = segment_trees(tile.cloud, terrain, fine_layers);
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].base.x(), 0.0f, 0.05f);
    EXPECT_NEAR(result.trees[0].stem_radius, kTrunk, 0.03f);

    SegmentOptions thin_only = fine_layers;  // flares are looked for under thick trunks only
    thin_only.buttressed_stem_radius = 1.0f;
    EXPECT_TRUE(segment_trees(tile.cloud, terrain, thin_only).trees.empty());
}

// A flared trunk as above that neighbours hide but for a 120-degree arc, which turns from +x at
// 1 m to -x at 2 m above the ground. The centroids of its slice points' lower and upper halves
// then lie 0.8 m apart at 0.5 m of height, as if it leaned 58 degrees, while its layers'
// circles stand one above the other.
TEST(SegmentTrees, ATrunkHalfHiddenIsFoundByItsLayersCentres) {
    ToyTile tile = test::flat_ground(-4, 5, -4, 5);
    for (float z = 0.0f; z <= 8.0f; z += 0.02f) {
        const float radius = 0.6f + 0.5f * std::max(0.0f, 2.5f - z) / 2.5f;
        const float facing = std::clamp(z - 1.0f, 0.0f, 1.0f) * std::numbers::pi_v<float>;
        for (int a = -72; a < 72; ++a) {
            const float t = static_cast<float>(a) * 2.5f * std::numbers::pi_v<float> / 180.0f;
            if (std::cos(t - facing) < 0.5f) continue;  // more than 60 degrees from the facing direction
            tile.add({radius * std::cos(t), radius * std::sin(t), z}, 1);
        }
    }
    test::classify_flat_ground(tile);
    const TreeSegmentation result = segment_trees(tile.cloud, analyse_terrain(tile.cloud, {}), {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].base.x(), 0.0f, 0.05f);
    EXPECT_NEAR(result.trees[0].base.y(), 0.0f, 0.05f);
}

// A thick straight trunk (radius 0.75 m) on a 20-degree slope, judged by one circle over the
// whole slice (layers as thick as the slice). The slice 1-2 m above the ground is 0.55 m higher
// on the trunk's uphill side than on its downhill side; cut by z, its lower half would lie
// 0.2 m downhill of the axis and its upper half as far uphill, as if it leaned 39 degrees.
TEST(SegmentTrees, AThickTrunkOnASlopeStandsUpright) {
    ToyTile tile;
    // Off the origin: a small tile whose ground crosses z = 0 would pass for a height-normalised one.
    test::add_ground(tile, 6, 15, -4, 5, 0.05f, 20.0f, 0.0f, [](float, float) { return false; });
    for (int a = 0; a < 144; ++a) {
        const float t = static_cast<float>(a) * 2.5f * std::numbers::pi_v<float> / 180.0f;
        const float x = 10.0f + 0.75f * std::cos(t), y = 0.75f * std::sin(t);
        for (float z = test::ground_height(x, y, 20.0f, 0.0f); z <= 8.0f; z += 0.02f) tile.add({x, y, z}, 1);
    }
    test::classify_ground(tile);
    SegmentOptions whole_slice;
    whole_slice.stem_layer_height = 2.0f;
    const TreeSegmentation result = segment_trees(tile.cloud, analyse_terrain(tile.cloud, {}), whole_slice);
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].stem_radius, 0.75f, 0.02f);
}

// A thick tree (stem radius 0.4 m) whose limb reaches 5.8 m out, into the crown of a thin
// neighbour (0.1 m). Through the thin tree's short stem the limb's far half (3-5 m out) is
// nearer than through its own trunk; a thick trunk's paths reach farther, so it stays there.
TEST(SegmentTrees, ALimbReachingOverAThinNeighbourStaysWithItsTrunk) {
    ToyTile tile = test::flat_ground(-4, 9, -4, 4);
    test::add_stem_and_ball(tile, 0, 0, 0.4f, 6, 2.5f, 0.15f, 1);
    const Eigen::Vector3f limb_start(0.4f, 0, 3), limb_end(5.8f, 0, 3.5f);
    for (float t = 0; t <= 1.0f; t += 0.004f)
        for (int a = 0; a < 12; ++a) {
            const float angle = static_cast<float>(a) * std::numbers::pi_v<float> / 6.0f;
            tile.add(limb_start + t * (limb_end - limb_start) + Eigen::Vector3f(0, 0.08f * std::cos(angle), 0.08f * std::sin(angle)), 1);
        }
    test::add_stem_and_ball(tile, 6.5f, 0, 0.1f, 3.5f, 1.0f, 0.1f, 2);
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});

    const auto shares = [&](const SegmentOptions& options) {
        const TreeSegmentation result = segment_trees(tile.cloud, terrain, options);
        EXPECT_EQ(result.trees.size(), 2u);
        // The two stems stand on one line of y: which id each gets is not the point here.
        const std::int32_t thick_id = result.trees.at(0).base.x() < 3.0f ? 1 : 2, thin_id = 3 - thick_id;
        std::size_t limb = 0, limb_kept = 0, thin = 0, thin_kept = 0;
        for (std::size_t i = 0; i < tile.truth.size(); ++i) {
            const Eigen::Vector3f& p = tile.cloud.positions[i];
            if (tile.truth[i] == 1 && p.x() > 3.0f && p.x() < 5.0f) {
                ++limb;
                limb_kept += result.tree_id[i] == thick_id;
            }
            if (tile.truth[i] == 2 && p.z() > 2.5f) {
                ++thin;
                thin_kept += result.tree_id[i] == thin_id;
            }
        }
        return std::pair(static_cast<double>(limb_kept) / static_cast<double>(limb), static_cast<double>(thin_kept) / static_cast<double>(thin));
    };
    const auto [limb_share, thin_share] = shares({});
    EXPECT_EQ(limb_share, 1.0);  // the far end of the limb is the thick tree's
    EXPECT_GT(thin_share, 0.95);  // and the thin tree keeps its crown
    SegmentOptions alike;
    alike.stem_reach_exponent = 0.0f;  // every stem reaching alike: the thin tree takes the limb's end
    const auto [limb_share_alike, thin_share_alike] = shares(alike);
    EXPECT_LT(limb_share_alike, 0.5);
    EXPECT_GT(thin_share_alike, 0.95);
}

// A tall thin tree (stem radius 0.1 m, 12.8 m) whose stem rises past the crown of a thick one
// (0.4 m, a 3 m ball around 5 m). The thick trunk's reach is sideways: the thin tree's stem and
// top above the ball stay its own, though a path from the thick stem through the ball and up
// the thin stem is not much longer.
TEST(SegmentTrees, ATallThinTreeKeepsItsTopBesideAThickOne) {
    ToyTile tile = test::flat_ground(-4, 6, -4, 4);
    test::add_stem_and_ball(tile, 0, 0, 0.4f, 5, 3.0f, 0.15f, 1);
    test::add_stem_and_ball(tile, 3.15f, 0, 0.1f, 12, 0.8f, 0.1f, 2);
    test::classify_flat_ground(tile);
    const TreeSegmentation result = segment_trees(tile.cloud, analyse_terrain(tile.cloud, {}), {});
    ASSERT_EQ(result.trees.size(), 2u);
    const std::int32_t thin_id = result.trees[0].base.x() > 1.5f ? 1 : 2;  // the stems stand on one line of y
    std::size_t top = 0, kept = 0;
    for (std::size_t i = 0; i < tile.truth.size(); ++i)
        if (tile.truth[i] == 2 && tile.cloud.positions[i].z() > 8.5f) {
            ++top;
            kept += result.tree_id[i] == thin_id;
        }
    EXPECT_EQ(kept, top);
}

// A trunk (radius 0.15 m) inside a willow's curtain: twigs hanging from 4 m down to 0.6 m on rings
// 0.23-0.95 m from the axis, 8 cm apart, so that at the 10 cm cluster distance trunk and
// curtain are one cluster in which the trunk holds an eighth of the points.
TEST(SegmentTrees, ATrunkInsideACurtainOfTwigsIsAStem) {
    ToyTile tile = test::flat_ground(-3, 3, -3, 3);
    test::add_stem_and_ball(tile, 0, 0, 0.15f, 6, 2.0f, 0.15f, 1);
    for (float ring = 0.23f; ring < 0.96f; ring += 0.08f) {
        const int twigs = static_cast<int>(2.0f * std::numbers::pi_v<float> * ring / 0.08f);
        for (int k = 0; k < twigs; ++k) {
            const float angle = 2.0f * std::numbers::pi_v<float> * (static_cast<float>(k) + 0.5f * ring) / static_cast<float>(twigs);
            for (float z = 0.6f; z <= 4.0f; z += 0.02f) tile.add({ring * std::cos(angle), ring * std::sin(angle), z}, 1);
        }
    }
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    const TreeSegmentation result = segment_trees(tile.cloud, terrain, {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].base.head<2>().norm(), 0.0f, 0.03f);
    EXPECT_NEAR(result.trees[0].stem_radius, 0.15f, 0.01f);
    SegmentOptions one_split;  // without the second, finer split the curtain hides the trunk
    one_split.stem_subcluster_distance = 0.0f;
    EXPECT_TRUE(segment_trees(tile.cloud, terrain, one_split).trees.empty());
}

// Two trunks 0.6 m apart under one crown (a multi-stemmed tree) are one tree, as wide as the two
// together; with no merging (by their distance or by the top they share), two that share the
// crown between them.
TEST(SegmentTrees, TrunksWithinAMetreAreOneTree) {
    ToyTile tile = test::flat_ground(-3, 4, -3, 3);
    test::add_stem_and_ball(tile, 0, 0, 0.08f, 5, 2.0f, 0.15f, 1);
    test::add_stem_and_ball(tile, 0.6f, 0, 0.08f, 5, 0.3f, 0.15f, 1);
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    const TreeSegmentation result = segment_trees(tile.cloud, terrain, {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].stem_radius, std::hypot(0.08f, 0.08f), 0.01f);  // their equivalent radius
    const SegmentationScore score = score_segmentation(tile.truth, result.tree_id, terrain.height_above_ground, 2.0f);
    EXPECT_EQ(score.f1, 1.0);
    SegmentOptions apart;
    apart.stem_merge_distance = 0.0f;
    apart.shared_top_stem_distance = 0.0f;
    EXPECT_EQ(segment_trees(tile.cloud, terrain, apart).trees.size(), 2u);
    apart.shared_top_stem_distance = SegmentOptions{}.shared_top_stem_distance;
    EXPECT_EQ(segment_trees(tile.cloud, terrain, apart).trees.size(), 1u);  // the shared top joins them
}

// A willow's curtain of hanging twigs can hold a circle of its trunk's size farther from the
// trunk than stem_merge_distance: here a bundle 1.4 m beside the trunk, hanging from the crown
// to the ground. Trunk and bundle split the one crown between them, and both their regions reach
// its top: one tree. Two trees as close whose tops lie 0.5 m apart across but 3.2 m apart in
// height (a short tree under a tall one's leaning crown) stay two.
TEST(SegmentTrees, TwoStemsWhoseTreesShareOneTopAreOneTree) {
    ToyTile willow = test::flat_ground(-3, 5, -3, 3);
    test::add_stem_and_ball(willow, 0, 0, 0.15f, 5, 0.0f, 0.15f, 1);
    test::add_stem_and_ball(willow, 1.4f, 0, 0.15f, 5, 0.0f, 0.15f, 1);
    for (float z = -2.0f; z <= 2.0f; z += 0.15f)  // the crown over both, top (0.7, 0, 8)
        for (float y = -2.0f; y <= 2.0f; y += 0.15f)
            for (float x = -2.0f; x <= 2.0f; x += 0.15f)
                if (x * x + y * y + z * z <= 4.0f) willow.add({0.7f + x, y, 6.0f + z}, 1);
    test::classify_flat_ground(willow);
    const Terrain willow_terrain = analyse_terrain(willow.cloud, {});
    const TreeSegmentation one = segment_trees(willow.cloud, willow_terrain, {});
    ASSERT_EQ(one.trees.size(), 1u);
    EXPECT_EQ(score_segmentation(willow.truth, one.tree_id, willow_terrain.height_above_ground, 2.0f).f1, 1.0);
    SegmentOptions not_joined;
    not_joined.shared_top_stem_distance = 0.0f;
    EXPECT_EQ(segment_trees(willow.cloud, willow_terrain, not_joined).trees.size(), 2u);

    ToyTile pair = test::flat_ground(-3, 5, -3, 3);
    test::add_stem_and_ball(pair, 0, 0, 0.15f, 7.5f, 0.0f, 0.15f, 1);
    test::add_stem_and_ball(pair, 1.5f, 0, 0.12f, 5.5f, 0.0f, 0.15f, 2);
    const auto add_ball = [](ToyTile& tile, float cx, float cz, float radius, std::int32_t id) {
        for (float z = -radius; z <= radius; z += 0.15f)
            for (float y = -radius; y <= radius; y += 0.15f)
                for (float x = -radius; x <= radius; x += 0.15f)
                    if (x * x + y * y + z * z <= radius * radius) tile.add({cx + x, y, cz + z}, id);
    };
    add_ball(pair, 0.5f, 8.5f, 1.0f, 1);  // the tall tree's crown, leaning toward the short one: top (0.5, 0, 9.5)
    add_ball(pair, 1.0f, 5.5f, 0.8f, 2);  // the short tree's: top (1.0, 0, 6.3)
    test::classify_flat_ground(pair);
    const Terrain pair_terrain = analyse_terrain(pair.cloud, {});
    const TreeSegmentation two = segment_trees(pair.cloud, pair_terrain, {});
    ASSERT_EQ(two.trees.size(), 2u);
    EXPECT_EQ(score_segmentation(pair.truth, two.tree_id, pair_terrain.height_above_ground, 2.0f).f1, 1.0);
}

// A multi-stemmed tree (a crape myrtle's): three trunks of 5 cm rising from one root collar at
// 18 degrees from vertical, each fanning out into a vase of upright twigs from 1.4 m, a crown
// above. A circle through the whole 1-2 m slice is the ring of the twigs, six times a trunk's
// radius; followed up from the bottom in thin layers each trunk is its own 5 cm. The tree is as
// wide as one stem of the same cross-section: sqrt(3) x 5 cm.
TEST(SegmentTrees, AMultiStemmedTreeIsAsWideAsItsTrunksTogether) {
    ToyTile tile = test::flat_ground(-3, 3, -3, 3);
    const float lean = std::tan(18.0f * std::numbers::pi_v<float> / 180.0f);
    const auto around = [](float radius, int k, int count) {
        const float t = static_cast<float>(k) * 2.0f * std::numbers::pi_v<float> / static_cast<float>(count);
        return Eigen::Vector2f(radius * std::cos(t), radius * std::sin(t));
    };
    for (int trunk = 0; trunk < 3; ++trunk) {
        const Eigen::Vector2f away = around(1.0f, trunk, 3);
        for (float z = 0.0f; z <= 2.5f; z += 0.02f)
            for (int a = 0; a < 36; ++a) {
                const Eigen::Vector2f p = lean * z * away + around(0.05f, a, 36);
                tile.add({p.x(), p.y(), z}, 1);
            }
        const Eigen::Vector2f vase_centre = lean * 1.4f * away;
        for (int twig = 0; twig < 24; ++twig) {
            for (float r = 0.05f; r < 0.3f; r += 0.02f) {  // from the trunk out ...
                const Eigen::Vector2f p = vase_centre + around(r, twig, 24);
                tile.add({p.x(), p.y(), 1.4f}, 1);
            }
            for (float z = 1.4f; z <= 2.5f; z += 0.005f) {  // ... and up
                const Eigen::Vector2f p = vase_centre + around(0.3f, twig, 24);
                tile.add({p.x(), p.y(), z}, 1);
            }
        }
    }
    for (float z = -1.2f; z <= 1.2f; z += 0.15f)  // the crown, a ball over the trunks' tops
        for (float y = -1.2f; y <= 1.2f; y += 0.15f)
            for (float x = -1.2f; x <= 1.2f; x += 0.15f)
                if (x * x + y * y + z * z <= 1.44f) tile.add({x, y, 3.5f + z}, 1);
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});

    const TreeSegmentation result = segment_trees(tile.cloud, terrain, {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].stem_radius, std::sqrt(3.0f) * 0.05f, 0.015f);
    SegmentOptions whole_slice;  // one trunk layer over the whole slice: the twigs' ring
    whole_slice.trunk_layer_height = 2.0f;
    const TreeSegmentation ring = segment_trees(tile.cloud, terrain, whole_slice);
    ASSERT_EQ(ring.trees.size(), 1u);
    EXPECT_GT(ring.trees[0].stem_radius, 0.25f);
}

TEST(SegmentTrees, AutomaticModeFollowsPointDensity) {
    const ToyTile airborne = two_crowns_airborne();
    const TreeSegmentation als = segment_trees(airborne.cloud, analyse_terrain(airborne.cloud, {}), {});
    EXPECT_EQ(als.mode_used, ScanMode::Airborne);
    EXPECT_NE(als.mode_reason.find("airborne"), std::string::npos);
    SegmentOptions forced;
    forced.mode = ScanMode::Terrestrial;
    const TreeSegmentation tls = segment_trees(airborne.cloud, analyse_terrain(airborne.cloud, {}), forced);
    EXPECT_EQ(tls.mode_used, ScanMode::Terrestrial);
    EXPECT_EQ(tls.mode_reason, "requested: tls");
    EXPECT_TRUE(tls.trees.empty());  // an airborne scan shows no stem circles
}

TEST(SegmentTrees, SingleTreeAndTreesBelowTheMinimumHeight) {
    ToyTile tile;
    test::add_ground(tile, 0, 10, 0, 10, 0.3f, 0.0f, 0.0f, [](float x, float y) { return std::hypot(x - 5, y - 5) < 2.2f; });
    test::add_cone_crown(tile, 5, 5, 9, 2, 0.3f, 0.0f, 0.0f, 1);
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    SegmentOptions options;
    options.mode = ScanMode::Airborne;
    EXPECT_EQ(segment_trees(tile.cloud, terrain, options).trees.size(), 1u);
    options.min_tree_height = 10.0f;
    const TreeSegmentation none = segment_trees(tile.cloud, terrain, options);
    EXPECT_TRUE(none.trees.empty());
    EXPECT_EQ(std::count(none.tree_id.begin(), none.tree_id.end(), 0), static_cast<std::ptrdiff_t>(tile.cloud.size()));
}

TEST(SegmentTrees, AllGroundAndEmptyTilesGiveNoTrees) {
    ToyTile ground;
    test::add_ground(ground, 0, 10, 0, 10, 0.2f, 10.0f, 0.1f, [](float, float) { return false; });
    for (ScanMode mode : {ScanMode::Automatic, ScanMode::Airborne, ScanMode::Terrestrial}) {
        SegmentOptions options;
        options.mode = mode;
        const TreeSegmentation result = segment_trees(ground.cloud, analyse_terrain(ground.cloud, {}), options);
        EXPECT_TRUE(result.trees.empty());
        EXPECT_EQ(result.tree_id.size(), ground.cloud.size());
    }
    const TreeSegmentation empty = segment_trees(PointCloud{}, analyse_terrain(PointCloud{}, {}), {});
    EXPECT_TRUE(empty.trees.empty());
    EXPECT_TRUE(empty.tree_id.empty());
}

TEST(SegmentTrees, RejectsBadOptionsAndAForeignTerrain) {
    const ToyTile tile = two_crowns_airborne();
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    const auto code_with = [&](const SegmentOptions& options) {
        return test::error_code_of([&] { segment_trees(tile.cloud, terrain, options); });
    };
    // The usage error for one option set to `value`, the others at their defaults.
    const auto rejects = [&](float SegmentOptions::*field, float value) {
        SegmentOptions bad;
        bad.*field = value;
        return code_with(bad) == ExitCode::Usage;
    };
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    EXPECT_TRUE(rejects(&SegmentOptions::chm_cell, 0.0f));
    EXPECT_TRUE(rejects(&SegmentOptions::cell_per_spacing, -0.1f));
    EXPECT_TRUE(rejects(&SegmentOptions::disc_per_spacing, 5.0f));
    EXPECT_TRUE(rejects(&SegmentOptions::disc_per_spacing, nan));
    EXPECT_TRUE(rejects(&SegmentOptions::sparse_disc_per_spacing, -1.0f));
    EXPECT_TRUE(rejects(&SegmentOptions::sparse_disc_per_spacing, nan));
    for (const float spacing : {-0.5f, 10.5f, nan, inf}) EXPECT_TRUE(rejects(&SegmentOptions::return_spacing, spacing)) << spacing;
    EXPECT_TRUE(rejects(&SegmentOptions::stem_slice_high, SegmentOptions{}.stem_slice_low));
    for (const float layer : {0.0f, 1e-9f, 100.0f, nan}) {
        EXPECT_TRUE(rejects(&SegmentOptions::stem_layer_height, layer)) << layer;
        EXPECT_TRUE(rejects(&SegmentOptions::trunk_layer_height, layer)) << layer;
    }
    for (const float distance : {-0.01f, 0.1f, nan}) EXPECT_TRUE(rejects(&SegmentOptions::stem_subcluster_distance, distance)) << distance;
    for (const float exponent : {-0.5f, 5.0f, nan}) EXPECT_TRUE(rejects(&SegmentOptions::stem_reach_exponent, exponent)) << exponent;
    for (const float share : {-0.1f, 1.5f, nan}) EXPECT_TRUE(rejects(&SegmentOptions::min_quarter_arc_share, share)) << share;
    for (const float reach : {0.0f, -1.0f, nan}) {
        EXPECT_TRUE(rejects(&SegmentOptions::stem_foot_reach, reach)) << reach;
        EXPECT_TRUE(rejects(&SegmentOptions::buttressed_foot_reach, reach)) << reach;
    }
    for (const float length : {-1.0f, inf, nan})
        for (const auto field :
             {&SegmentOptions::stem_merge_distance, &SegmentOptions::attach_gap, &SegmentOptions::detached_min_height,
              &SegmentOptions::shared_top_stem_distance, &SegmentOptions::shared_top_distance, &SegmentOptions::buttressed_stem_radius})
            EXPECT_TRUE(rejects(field, length)) << length;
    SegmentOptions no_voxels;
    no_voxels.min_detached_voxels = 0;
    EXPECT_EQ(code_with(no_voxels), ExitCode::Usage);
    EXPECT_EQ(test::error_code_of([&] { segment_trees(PointCloud{}, terrain, {}); }), ExitCode::Internal);
}

TEST(SegmentTrees, ScanModeNames) {
    EXPECT_EQ(parse_scan_mode("als"), ScanMode::Airborne);
    EXPECT_EQ(parse_scan_mode("tls"), ScanMode::Terrestrial);
    EXPECT_EQ(parse_scan_mode("auto"), ScanMode::Automatic);
    EXPECT_STREQ(scan_mode_name(ScanMode::Terrestrial), "tls");
    EXPECT_EQ(test::error_code_of([] { parse_scan_mode("mls"); }), ExitCode::Usage);
}

// The stand presets set the airborne settings and nothing else: broadleaf is the defaults,
// conifer takes every window maximum on the unsmoothed CHM with crowns at most 3.5 m wide.
TEST(SegmentTrees, StandPresets) {
    SegmentOptions custom;
    custom.min_tree_height = 4.0f;
    custom.max_crown_radius = 9.0f;
    const SegmentOptions conifer = with_stand_type(custom, parse_stand_type("conifer"));
    EXPECT_EQ(conifer.min_top_prominence, 0.0f);
    EXPECT_EQ(conifer.top_prominence_ratio, 0.0f);
    EXPECT_EQ(conifer.chm_smoothing, 0.0f);
    EXPECT_EQ(conifer.max_crown_radius, 3.5f);
    EXPECT_EQ(conifer.stem_reach_exponent, 0.0f);
    EXPECT_EQ(conifer.min_tree_height, 4.0f);
    const SegmentOptions broadleaf = with_stand_type(conifer, parse_stand_type("broadleaf"));
    const SegmentOptions defaults;
    EXPECT_EQ(broadleaf.min_top_prominence, defaults.min_top_prominence);
    EXPECT_EQ(broadleaf.top_prominence_ratio, defaults.top_prominence_ratio);
    EXPECT_EQ(broadleaf.chm_smoothing, defaults.chm_smoothing);
    EXPECT_EQ(broadleaf.max_crown_radius, defaults.max_crown_radius);
    EXPECT_EQ(broadleaf.stem_reach_exponent, defaults.stem_reach_exponent);
    EXPECT_EQ(broadleaf.min_tree_height, 4.0f);
    EXPECT_EQ(test::error_code_of([] { parse_stand_type("palm"); }), ExitCode::Usage);
}

// A limb that droops to the ground, 0.7 m from nothing (docs/segment.md: a fig's limb on a
// crowded plot): in the slice 1-2 m above the ground its points fill a half circle up to
// 1.25 m and above that only the narrow strip where the limb rises. The whole slice fits the
// half circle, and the strip stands over the middle of the arc, so the circle passes as an
// upright stem unless every upper quarter of the slice must hold its arc too. A trunk beside
// it holds its circle all the way up.
TEST(SegmentTrees, ALimbWhoseArcFillsOnlyTheFootOfTheSliceIsNoStem) {
    ToyTile tile = test::flat_ground(-3, 5, -3, 3);
    const auto on_circle = [](float radius, float degrees) {
        const float t = degrees * std::numbers::pi_v<float> / 180.0f;
        return Eigen::Vector2f(radius * std::cos(t), radius * std::sin(t));
    };
    for (float z = 0.0f; z <= 1.25f; z += 0.02f)  // the limb's half circle, down to the ground
        for (float a = 0.0f; a <= 180.0f; a += 2.0f) {
            const Eigen::Vector2f p = on_circle(0.7f, a);
            tile.add({p.x(), p.y(), z}, 1);
        }
    for (float z = 1.25f; z <= 4.0f; z += 0.01f)  // where it rises: 6 degrees of the arc
        for (float a = 92.0f; a <= 98.0f; a += 2.0f) {
            const Eigen::Vector2f p = on_circle(0.7f, a);
            tile.add({p.x(), p.y(), z}, 1);
        }
    for (float z = 0.0f; z <= 4.0f; z += 0.02f)  // a trunk 3 m away
        for (float a = 0.0f; a < 360.0f; a += 10.0f) {
            const Eigen::Vector2f p = Eigen::Vector2f(3.0f, 0.0f) + on_circle(0.15f, a);
            tile.add({p.x(), p.y(), z}, 2);
        }
    test::classify_flat_ground(tile);
    const Terrain terrain = analyse_terrain(tile.cloud, {});

    const TreeSegmentation result = segment_trees(tile.cloud, terrain, {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].stem_radius, 0.15f, 0.02f);
    SegmentOptions unchecked;
    unchecked.min_quarter_arc_share = 0.0f;
    EXPECT_EQ(segment_trees(tile.cloud, terrain, unchecked).trees.size(), 2u);
}

// A clump of twigs under a broad crown, far from its trunk: a column of twigs 7 cm around
// reaches the ground, a twig arc 26 cm around the same axis lies in the next layer of the slice,
// and one twig rises through the rest of the slice to the crown. Two of the slice's four layers
// hold circles centred within half a radius of each other, but of radii 3.7 times apart: no
// trunk. A trunk 3 m away is the one tree.
TEST(SegmentTrees, LayersWhoseCirclesDifferInGirthAreNoStem) {
    ToyTile tile = test::flat_ground(-3, 5, -3, 3);
    const auto on_circle = [](float radius, float degrees) {
        const float t = degrees * std::numbers::pi_v<float> / 180.0f;
        return Eigen::Vector2f(radius * std::cos(t), radius * std::sin(t));
    };
    for (float z = 0.35f; z < 1.25f; z += 0.02f)  // the column, from near the ground into the slice's first layer
        for (float a = 0.0f; a < 360.0f; a += 30.0f) {
            const Eigen::Vector2f p = on_circle(0.07f, a);
            tile.add({p.x(), p.y(), z}, 1);
        }
    for (float z = 1.26f; z < 1.5f; z += 0.02f)  // the arc, in the second layer
        for (float a = 0.0f; a <= 120.0f; a += 4.0f) {
            const Eigen::Vector2f p = on_circle(0.26f, a);
            tile.add({p.x(), p.y(), z}, 1);
        }
    for (float r = 0.07f; r <= 0.26f; r += 0.02f) tile.add({r, 0.0f, 1.25f}, 1);  // a twig joining them
    for (float z = 1.5f; z <= 6.0f; z += 0.03f) tile.add({0.26f, 0.0f, z}, 1);     // the twig up to the crown
    for (float z = 0.0f; z <= 6.0f; z += 0.02f)                                     // the trunk 3 m away
        for (float a = 0.0f; a < 360.0f; a += 10.0f) {
            const Eigen::Vector2f p = Eigen::Vector2f(3.0f, 0.0f) + on_circle(0.15f, a);
            tile.add({p.x(), p.y(), z}, 2);
        }
    test::classify_flat_ground(tile);

    const TreeSegmentation result = segment_trees(tile.cloud, analyse_terrain(tile.cloud, {}), {});
    ASSERT_EQ(result.trees.size(), 1u);
    EXPECT_NEAR(result.trees[0].base.x(), 3.0f, 0.05f);
    EXPECT_NEAR(result.trees[0].stem_radius, 0.15f, 0.02f);
}
