// Tile lists (folder, pattern, list file; sorted, unique names), shards (disjoint, complete,
// parse errors), the header point count and the memory refusal.
#include "core/cloud_io.hpp"
#include "support/test_support.hpp"
#include "survey/memory_estimate.hpp"
#include "survey/merge.hpp"
#include "survey/tile_list.hpp"

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
    EXPECT_EQ(survey::header_point_count(dir / "t.las"), 1000u);
    EXPECT_EQ(survey::header_point_count(dir / "t.ply"), 1000u);
    EXPECT_FALSE(survey::refuse_if_too_big(dir / "t.las", 1e9).has_value());
    const auto refusal = survey::refuse_if_too_big(dir / "t.las", 1000.0);
    ASSERT_TRUE(refusal.has_value());
    EXPECT_NE(refusal->find("1000 points"), std::string::npos) << *refusal;
    EXPECT_NE(refusal->find("retile"), std::string::npos) << *refusal;
    EXPECT_DOUBLE_EQ(survey::parse_memory_size("2G"), 2.0 * 1024 * 1024 * 1024);
    EXPECT_DOUBLE_EQ(survey::parse_memory_size("512m"), 512.0 * 1024 * 1024);
    for (const char* bad : {"", "0", "-1G", "2X", "G", "1GB"})
        EXPECT_EQ(test::error_code_of([&] { survey::parse_memory_size(bad); }), ExitCode::Usage) << bad;
    test::write_text(dir / "fake.las", "not a las file at all, just text that is long enough to look like a header to a careless reader"
                                       "..........................................................................................."
                                       "...........................................................................................");
    EXPECT_EQ(test::error_code_of([&] { survey::header_point_count(dir / "fake.las"); }), ExitCode::InvalidInput);
}

TEST(GlobalTreeId, SortsByTileThenTree) {
    EXPECT_EQ(survey::global_tree_id("tile_0_100", 7), "tile_0_100/000007");
    EXPECT_LT(survey::global_tree_id("a", 9), survey::global_tree_id("a", 10));
}
