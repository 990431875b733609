// Tile lists (folder, pattern, list file; sorted, unique names), shards (disjoint, complete,
// parse errors), the header point count and the memory refusal.
#include "core/cloud_header.hpp"
#include "core/cloud_io.hpp"
#include "core/memory_limit.hpp"
#include "support/test_support.hpp"
#include "survey/buffered_tile.hpp"
#include "survey/merge.hpp"
#include "survey/tile_list.hpp"
#include "survey/tree_id.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace treelobes;
using test::TempDir;
namespace fs = std::filesystem;

namespace {

void touch(const fs::path& path) { test::write_text(path, "0 0 0\n"); }

std::vector<std::string> names(const std::vector<fs::path>& tiles) {
    std::vector<std::string> out;
    for (const auto& t : tiles) out.push_back(t.filename().string());
    return out;
}

}  // namespace

TEST(TileList, FolderPatternAndListGiveSortedTiles) {
    TempDir dir;
    fs::create_directories(dir / "tiles");
    for (const char* name : {"c.xyz", "a.xyz", "b.xyz", "notes.md"}) touch(dir / "tiles" / name);
    const std::vector<std::string> expected{"a.xyz", "b.xyz", "c.xyz"};
    EXPECT_EQ(names(survey::list_tiles((dir / "tiles").string())), expected);
    EXPECT_EQ(names(survey::list_tiles((dir / "tiles" / "*.xyz").string())), expected);
    test::write_text(dir / "tiles.txt", "# survey\ntiles/c.xyz\n\ntiles/a.xyz\ntiles/b.xyz\ntiles/a.xyz\n");
    EXPECT_EQ(names(survey::list_tiles((dir / "tiles.txt").string())), expected);
}

TEST(TileList, BadSourcesAreRefused) {
    TempDir dir;
    EXPECT_EQ(test::error_code_of([&] { survey::list_tiles((dir / "missing").string()); }), ExitCode::InvalidInput);
    fs::create_directories(dir / "empty");
    EXPECT_EQ(test::error_code_of([&] { survey::list_tiles((dir / "empty").string()); }), ExitCode::InvalidInput);
    test::write_text(dir / "list.txt", "nowhere.las\n");
    EXPECT_EQ(test::error_code_of([&] { survey::list_tiles((dir / "list.txt").string()); }), ExitCode::InvalidInput);
    fs::create_directories(dir / "a");
    fs::create_directories(dir / "b");
    touch(dir / "a" / "t.xyz");
    touch(dir / "b" / "t.xyz");
    test::write_text(dir / "same.txt", "a/t.xyz\nb/t.xyz\n");  // two tiles, one output folder
    EXPECT_EQ(test::error_code_of([&] { survey::list_tiles((dir / "same.txt").string()); }), ExitCode::Usage);
}

TEST(Shards, AreDisjointAndTakeEveryTile) {
    std::vector<fs::path> tiles;
    for (int i = 0; i < 10; ++i) tiles.push_back(test::numbered("t", static_cast<std::size_t>(i)));
    std::multiset<std::string> seen;
    for (std::size_t i = 0; i < 4; ++i)
        for (const auto& t : survey::shard_tiles(tiles, survey::parse_shard(std::to_string(i) + "/4"))) seen.insert(t.string());
    EXPECT_EQ(seen.size(), tiles.size());
    for (const auto& t : tiles) EXPECT_EQ(seen.count(t.string()), 1u);
    EXPECT_EQ(survey::shard_tiles(tiles, survey::parse_shard("1/4")), (std::vector<fs::path>{"t1", "t5", "t9"}));
    for (const char* bad : {"4/4", "1/0", "a/4", "1", "-1/4", "1/4x", ""})
        EXPECT_EQ(test::error_code_of([&] { survey::parse_shard(bad); }), ExitCode::Usage) << bad;
}

TEST(MemoryEstimate, HeaderCountAndRefusal) {
    TempDir dir;
    PointCloud cloud;
    for (int i = 0; i < 1000; ++i) cloud.positions.emplace_back(static_cast<float>(i % 10), static_cast<float>(i / 10), 1.0f);
    write_point_cloud(cloud, dir / "t.las");
    write_point_cloud(cloud, dir / "t.ply");
    EXPECT_EQ(header_point_count(dir / "t.las"), 1000u);
    EXPECT_EQ(header_point_count(dir / "t.ply"), 1000u);
    EXPECT_FALSE(memory_refusal(header_point_count(dir / "t.las"), kTileBytesPerPoint, 1e9).has_value());
    const auto refusal = memory_refusal(header_point_count(dir / "t.las"), kTileBytesPerPoint, 1000.0);
    ASSERT_TRUE(refusal.has_value());
    EXPECT_NE(refusal->find("1000 points"), std::string::npos) << *refusal;
    EXPECT_NE(refusal->find("retile"), std::string::npos) << *refusal;
    EXPECT_DOUBLE_EQ(parse_memory_size("2G"), 2.0 * 1024 * 1024 * 1024);
    EXPECT_DOUBLE_EQ(parse_memory_size("512m"), 512.0 * 1024 * 1024);
    for (const char* bad : {"", "0", "-1G", "2X", "G", "1GB"})
        EXPECT_EQ(test::error_code_of([&] { parse_memory_size(bad); }), ExitCode::Usage) << bad;
    test::write_text(dir / "fake.las",
                     "not a las file at all, just text that is long enough to look like a header to a careless reader"
                     "..........................................................................................."
                     "...........................................................................................");
    EXPECT_EQ(test::error_code_of([&] { header_point_count(dir / "fake.las"); }), ExitCode::InvalidInput);
}

TEST(StableTreeId, OneCentimetreCellOfTheBase) {
    EXPECT_EQ(survey::stable_tree_id(500012.345, 5400056.789), "500012.34_5400056.78");
    EXPECT_EQ(survey::stable_tree_id(-0.005, -12.341), "-0.01_-12.35");
    EXPECT_EQ(survey::stable_tree_id(0.0, 7.0), "0.00_7.00");
    // A base on a cell edge (LAS coordinates on a 1 cm grid) seen through another float frame.
    for (double noise : {-2e-6, 0.0, 2e-6})
        EXPECT_EQ(survey::stable_tree_id(500012.34 + noise, 5400056.70 - noise), "500012.34_5400056.70");
    // Two bases in one cell: the lower keeps the id.
    const auto ids = survey::stable_tree_ids({{10.001, 20.001, 301.0}, {10.004, 20.002, 300.0}, {11.0, 20.0, 299.0}});
    EXPECT_EQ(ids, (std::vector<std::string>{"10.00_20.00~2", "10.00_20.00", "11.00_20.00"}));
}

TEST(BufferedTile, CoreFromRetileNameIsHalfOpen) {
    const survey::TileCore core = survey::core_from_retile_name("tiles/tile_500040_5400000.las", 40.0);
    EXPECT_TRUE(core.holds(500040.0, 5400000.0));
    EXPECT_TRUE(core.holds(500079.999, 5400039.999));
    EXPECT_FALSE(core.holds(500080.0, 5400010.0));  // the next square's
    EXPECT_FALSE(core.holds(500050.0, 5400040.0));
    EXPECT_EQ(survey::core_from_retile_name("t_-20.50_3.25.las", 1.0).min_x, -20.5);
    EXPECT_EQ(test::error_code_of([] { survey::core_from_retile_name("plot.las", 40.0); }), ExitCode::Usage);
    EXPECT_EQ(test::error_code_of([] { survey::core_from_retile_name("t_1_y.las", 40.0); }), ExitCode::Usage);
}

TEST(BufferedTile, ReadsNeighbourPointsWithinTheBufferOnly) {
    TempDir dir;
    // Three 10 m squares in a row, a point every metre; the middle one is the tile.
    for (int t = 0; t < 3; ++t) {
        PointCloud cloud;
        cloud.origin = {10.0 * t, 0.0, 0.0};
        for (int i = 0; i < 10; ++i)
            for (int j = 0; j < 10; ++j) cloud.positions.emplace_back(static_cast<float>(i) + 0.5f, static_cast<float>(j) + 0.5f, 1.0f);
        write_point_cloud(cloud, dir / ("t_" + std::to_string(10 * t) + "_0.las"));
    }
    PointCloud far;
    far.origin = {200.0, 0.0, 0.0};
    far.positions.emplace_back(0.5f, 0.5f, 1.0f);
    write_point_cloud(far, dir / "t_200_0.las");
    const fs::path input = dir / "t_10_0.las";
    const survey::TileCore core = survey::core_from_retile_name(input, 10.0);
    const auto candidates = survey::list_tiles(dir.path().string());
    // Each neighbour: 100 points over bounds 9 m wide, of which 1.5 m lie in the box (the 40 points read are a grid edge effect).
    EXPECT_EQ(survey::estimate_buffer_points(input, core, 2.0, candidates), 34u);
    const survey::BufferedTile buffered = survey::add_buffer(read_point_cloud(input), input, core, 2.0, candidates);
    EXPECT_EQ(buffered.own_points, 100u);
    EXPECT_EQ(buffered.cloud.size(), 140u);  // columns x = 8.5, 9.5 and 20.5, 21.5
    EXPECT_EQ(buffered.neighbours_read.size(), 2u);
    EXPECT_EQ(buffered.neighbours_skipped, 1u);  // t_200_0: its header bounds miss the box
    for (std::size_t i = buffered.own_points; i < buffered.cloud.size(); ++i) {
        const double x = buffered.cloud.global(i).x();
        EXPECT_TRUE((x >= 8.0 && x < 10.0) || (x >= 20.0 && x <= 22.0)) << x;
    }
}
