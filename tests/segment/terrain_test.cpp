// Terrain: ground filter and DTM on a steep rough slope under crowns, detection of classified
// and height-normalised tiles, the grid outputs, and bad input.
#include "segment/terrain.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "render/image.hpp"
#include "support/test_support.hpp"
#include "toy_tiles.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>

using namespace treelobes;
using test::ToyTile;

namespace {

constexpr float kSlope = 20.0f, kRoughness = 0.3f;

// 40 x 40 m of 20-degree slope, 0.5 m ground spacing, three crowns; under the biggest crown
// no ground return reaches the ground (a 6 x 6 m hole the DTM must fill).
ToyTile sloped_forest() {
    ToyTile tile;
    test::add_ground(tile, 0, 40, 0, 40, 0.5f, kSlope, kRoughness,
                     [](float x, float y) { return std::abs(x - 20) < 3 && std::abs(y - 20) < 3; });
    test::add_cone_crown(tile, 20, 20, 18, 4, 0.3f, kSlope, kRoughness, 1);
    test::add_cone_crown(tile, 8, 30, 12, 3, 0.3f, kSlope, kRoughness, 2);
    test::add_cone_crown(tile, 32, 9, 15, 3.5f, 0.3f, kSlope, kRoughness, 3);
    return tile;
}

struct DtmError {
    double mean = 0, max = 0;
};

// Error of the DTM against the true ground over the tile less a margin, inside or outside the
// hole under the big crown.
DtmError dtm_error(const DtmGrid& dtm, float margin, bool in_hole) {
    DtmError e;
    std::size_t n = 0;
    for (float y = margin; y <= 40 - margin; y += 0.7f)
        for (float x = margin; x <= 40 - margin; x += 0.7f) {
            if ((std::abs(x - 20) < 3 && std::abs(y - 20) < 3) != in_hole) continue;
            const double d = std::abs(dtm.height_at(x, y) - test::ground_height(x, y, kSlope, kRoughness));
            e.mean += d;
            e.max = std::max(e.max, d);
            ++n;
        }
    e.mean /= static_cast<double>(n);
    return e;
}

}  // namespace

TEST(Terrain, FiltersGroundOnARoughTwentyDegreeSlope) {
    const ToyTile tile = sloped_forest();
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    EXPECT_EQ(terrain.ground_source, "filtered");
    const DtmError seen = dtm_error(terrain.dtm, 1.0f, false);
    EXPECT_LT(seen.mean, 0.03);
    EXPECT_LT(seen.max, 0.12);
    // In the hole the bumps (0.3 m) cannot be known; the slope across it is kept.
    const DtmError hole = dtm_error(terrain.dtm, 1.0f, true);
    EXPECT_LT(hole.mean, 0.25);
    EXPECT_LT(hole.max, kRoughness + 0.1);
    std::size_t crown_as_ground = 0, crown_points = 0, ground_missed = 0, ground_points = 0;
    for (std::size_t i = 0; i < tile.cloud.size(); ++i) {
        if (tile.truth[i]) {
            ++crown_points;
            crown_as_ground += terrain.is_ground[i];
        } else {
            ++ground_points;
            ground_missed += !terrain.is_ground[i];
        }
    }
    EXPECT_EQ(crown_as_ground, 0u);
    EXPECT_LT(static_cast<double>(ground_missed) / ground_points, 0.01);
    // The big crown's top is 18 m above the ground under it.
    float highest = 0;
    for (std::size_t i = 0; i < tile.cloud.size(); ++i)
        if (tile.truth[i] == 1) highest = std::max(highest, terrain.height_above_ground[i]);
    EXPECT_NEAR(highest, 18.0f, 0.25f);
}

TEST(Terrain, UsesAnExistingGroundClassAndCanIgnoreIt) {
    ToyTile tile = sloped_forest();
    // A deliberately odd classification: only the ground of the lower half is class 2.
    for (std::size_t i = 0; i < tile.cloud.size(); ++i)
        tile.cloud.classification.push_back(!tile.truth[i] && tile.cloud.positions[i].x() < 20 ? 2 : 1);
    const Terrain classified = analyse_terrain(tile.cloud, {});
    EXPECT_EQ(classified.ground_source, "classified");
    std::size_t class_two = 0;
    for (auto c : tile.cloud.classification) class_two += c == 2;
    EXPECT_EQ(classified.ground_points, class_two);

    TerrainOptions ignore;
    ignore.use_classification = false;
    const Terrain filtered = analyse_terrain(tile.cloud, ignore);
    EXPECT_EQ(filtered.ground_source, "filtered");
    EXPECT_GT(filtered.ground_points, class_two * 3 / 2);
}

TEST(Terrain, DetectsHeightNormalisedTiles) {
    ToyTile tile;
    test::add_ground(tile, 0, 30, 0, 30, 0.5f, 0.0f, 0.1f, [](float, float) { return false; });
    test::add_cone_crown(tile, 15, 15, 14, 3, 0.3f, 0.0f, 0.1f, 1);
    // Stored in a local frame: the file's z = local z + origin z.
    tile.cloud.origin = Eigen::Vector3d(500000.0, 4000000.0, 50.0);
    for (auto& p : tile.cloud.positions) p.z() -= 50.0f;
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    EXPECT_EQ(terrain.ground_source, "normalised");
    for (std::size_t i = 0; i < tile.cloud.size(); ++i)
        ASSERT_NEAR(terrain.height_above_ground[i], tile.cloud.positions[i].z() + 50.0f, 1e-4f);
    EXPECT_NEAR(terrain.dtm.height_at(3, 3), -50.0f, 1e-6f);

    // The same terrain 300 m up is not normalised.
    for (auto& p : tile.cloud.positions) p.z() += 300.0f;
    EXPECT_EQ(analyse_terrain(tile.cloud, {}).ground_source, "filtered");
}

TEST(Terrain, BilinearHeightIsExactOnAPlane) {
    DtmGrid dtm;
    dtm.origin = Eigen::Vector2d(10, 20);
    dtm.cell_size = 2;
    dtm.columns = 4;
    dtm.rows = 3;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) dtm.heights.push_back(0.5f * (11 + 2 * c) - 0.25f * (21 + 2 * r));
    EXPECT_NEAR(dtm.height_at(13.3f, 23.7f), 0.5f * 13.3f - 0.25f * 23.7f, 1e-4f);
    // Outside the centres the edge cells hold.
    EXPECT_NEAR(dtm.height_at(0.0f, 23.7f), dtm.height_at(11.0f, 23.7f), 1e-5f);
    dtm.heights[0] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_TRUE(std::isfinite(dtm.height_at(11.0f, 21.0f)) == false);
    EXPECT_TRUE(std::isfinite(dtm.height_at(12.0f, 22.0f)));
    EXPECT_TRUE(std::isnan(DtmGrid{}.height_at(0, 0)));
}

TEST(Terrain, WritesAsciiGridNorthRowFirstAndHillshade) {
    DtmGrid dtm;
    dtm.origin = Eigen::Vector2d(-1, -2);
    dtm.cell_size = 1;
    dtm.columns = 3;
    dtm.rows = 2;
    dtm.heights = {1, 2, 3, 4, 5, std::numeric_limits<float>::quiet_NaN()};
    test::TempDir dir;
    write_ascii_grid(dtm, Eigen::Vector3d(1000, 2000, 100), dir / "dtm.asc");
    EXPECT_EQ(read_file(dir / "dtm.asc"),
              "ncols 3\nnrows 2\nxllcorner 999.000\nyllcorner 1998.000\ncellsize 1\nNODATA_value -9999\n"
              "104.000 105.000 -9999\n101.000 102.000 103.000\n");
    write_hillshade_png(dtm, dir / "dtm.png");
    const render::Image image = render::read_png(dir / "dtm.png");
    EXPECT_EQ(image.width, 3);
    EXPECT_EQ(image.height, 2);
    EXPECT_EQ(test::error_code_of([&] { write_ascii_grid(DtmGrid{}, {0, 0, 0}, dir / "x.asc"); }), ExitCode::InvalidInput);
}

// A few points spread over a wide extent (laspy's simple.laz: 1,065 points on 3.4 x 4.6 km)
// must not take a 1 m grid of millions of cells: the cell grows to keep at most 4 per point.
TEST(Terrain, AFewPointsOverAWideExtentGetACoarserGrid) {
    ToyTile tile;
    test::add_ground(tile, 0, 2000, 0, 3000, 100.0f, 2.0f, 0.0f, [](float, float) { return false; });  // 651 points
    const Terrain terrain = analyse_terrain(tile.cloud, {});
    EXPECT_EQ(terrain.ground_source, "filtered");
    EXPECT_LE(static_cast<double>(terrain.dtm.columns) * terrain.dtm.rows,
              4.0 * static_cast<double>(tile.cloud.size()) * 1.1);  // + the edge cells
    EXPECT_NEAR(terrain.dtm.cell_size, grid_cell_for_points(tile.cloud, 1.0f), 1e-6f);
    EXPECT_GT(terrain.dtm.cell_size, 30.0f);
    // Dense enough points keep the requested cell.
    EXPECT_EQ(grid_cell_for_points(sloped_forest().cloud, 1.0f), 1.0f);
}

TEST(Terrain, EmptyCloudGivesAnEmptyTerrain) {
    const Terrain terrain = analyse_terrain(PointCloud{}, {});
    EXPECT_TRUE(terrain.dtm.empty());
    EXPECT_TRUE(terrain.height_above_ground.empty());
    EXPECT_EQ(terrain.ground_source, "none");
}

TEST(Terrain, RejectsNonFiniteCoordinatesAndBadOptions) {
    ToyTile tile;
    test::add_ground(tile, 0, 5, 0, 5, 0.5f, 0.0f, 0.0f, [](float, float) { return false; });
    tile.cloud.positions[7].y() = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(test::error_code_of([&] { analyse_terrain(tile.cloud, {}); }), ExitCode::InvalidInput);
    TerrainOptions bad;
    bad.cell_size = 0;
    EXPECT_EQ(test::error_code_of([&] { analyse_terrain(PointCloud{}, bad); }), ExitCode::Usage);
}
