// End to end over a small synthetic survey: `batch` in 4 shards (one after the other, and with
// GNU parallel), merged in any order, gives the bytes of one unsharded run; a batch killed with
// kill -9 at a random moment and run again finishes without redoing a tile and gives the same
// bytes; a bad tile is listed and the rest goes on; --max-memory refuses tiles before loading;
// retile cuts tiles that batch then runs.
#include "core/cloud_io.hpp"
#include "support/test_support.hpp"
#include "survey/completion.hpp"
#include "survey_fixture.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cstdio>
#include <map>
#include <random>
#include <thread>

using namespace treelobes;
using namespace treelobes::test;
namespace fs = std::filesystem;

extern char** environ;

namespace {

constexpr int kTiles = 4;

struct Reference {
    fs::path tiles, merged;
    double batch_seconds = 0;
};

std::string batch_command(const fs::path& tiles, const fs::path& out, const std::string& extra = "", const std::string& global = "") {
    return cli() + " --log-level warn " + global + " batch '" + tiles.string() + "' --out '" + out.string() + "' " + extra + " " +
           kTileOptions;
}

std::string merge_command(const std::vector<fs::path>& dirs, const fs::path& out) {
    std::string command = cli() + " --log-level warn merge";
    for (const auto& d : dirs) command += " '" + d.string() + "'";
    return command + " --out '" + out.string() + "' >/dev/null";
}

// One unsharded batch and its merge, made once for the ctest run (test::shared_fixture).
const Reference& reference() {
    static const Reference made = [] {
        const fs::path dir = shared_fixture("survey_cli_reference", [](const fs::path& d) {
            const fs::path tiles = make_survey(d, kTiles, 3, 20.0);
            const auto start = std::chrono::steady_clock::now();
            EXPECT_EQ(shell(batch_command(tiles, d / "single") + " >/dev/null"), 0);
            write_text(d / "batch_seconds",
                       std::to_string(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()));
            EXPECT_EQ(shell(merge_command({d / "single"}, d / "single_merged")), 0);
        });
        return Reference{dir / "tiles", dir / "single_merged", std::stod(file_bytes(dir / "batch_seconds"))};
    }();
    return made;
}

}  // namespace

TEST(SurveyCli, SingleRunMergesEveryTree) {
    const Reference& r = reference();
    const auto summary = nlohmann::json::parse(file_bytes(r.merged / "summary.json"));
    EXPECT_EQ(summary["tiles_merged"], kTiles);
    EXPECT_GT(summary["trees"].get<int>(), kTiles);  // 3 trees per tile, a few may fail
    EXPECT_EQ(summary["trees"], summary["counts"]["trees"]);
    EXPECT_EQ(summary["forest_trees"], summary["counts"]["trees_modelled"]);  // trees measured only have no skeleton
    const std::string csv = file_bytes(r.merged / "trees.csv");
    EXPECT_EQ(csv.rfind("global_id,tile,tree_id,x,y", 0), 0u) << csv.substr(0, 80);
    const auto crowns = nlohmann::json::parse(file_bytes(r.merged / "crowns.geojson"))["features"];
    const auto points = nlohmann::json::parse(file_bytes(r.merged / "trees.geojson"))["features"];
    ASSERT_EQ(crowns.size(), points.size());
    for (std::size_t i = 0; i < crowns.size(); ++i) {  // the same trees in the same order, each with its tile
        EXPECT_EQ(crowns[i]["properties"], points[i]["properties"]);
        EXPECT_TRUE(crowns[i]["properties"]["tile"].is_string());
    }
    EXPECT_NE(csv.find("\n5000"), std::string::npos);  // survey-wide ids from the stem base: "<x>_<y>" of its 1 cm cell
    EXPECT_NE(csv.find(",t_3,"), std::string::npos);
}

// A tile folder whose JSON parses but is not what `tile` writes (a field missing or of another
// type) stops the merge with one line naming the tile and exit 2, and no output folder.
TEST(SurveyCli, MalformedTileOutputsAreOneLineErrors) {
    const Reference& r = reference();
    TempDir dir;
    fs::copy(r.merged.parent_path() / "single", dir / "batch", fs::copy_options::recursive);
    const fs::path tile = dir / "batch" / "t_1";
    const auto summary = nlohmann::json::parse(file_bytes(tile / "summary.json"));
    for (const auto& damage : std::vector<std::function<void(nlohmann::json&)>>{
                 [](nlohmann::json& s) { s["counts"] = 5; },
                 [](nlohmann::json& s) {
                     s["buffer"] = {{"trees_at_edge", {1}}};
                 },
                 [](nlohmann::json& s) { s.erase("options"); },
                 [](nlohmann::json& s) { s["counts"]["trees"] = 1e30; },  // no int holds it
         }) {
        nlohmann::json damaged = summary;
        damage(damaged);
        write_text(tile / "summary.json", damaged.dump());
        const CommandResult result = run_cli("merge '" + (dir / "batch").string() + "' --out '" + (dir / "out").string() + "'");
        EXPECT_EQ(result.exit_code, 2) << result.err;
        EXPECT_NE(result.err.find("t_1"), std::string::npos) << result.err;
        EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
        EXPECT_FALSE(fs::exists(dir / "out"));
    }
    // A tile made before crowns.geojson existed.
    write_text(tile / "summary.json", summary.dump());
    fs::remove(tile / "crowns.geojson");
    const CommandResult older = run_cli("merge '" + (dir / "batch").string() + "' --out '" + (dir / "out").string() + "'");
    EXPECT_EQ(older.exit_code, 2) << older.err;
    EXPECT_NE(older.err.find("t_1/crowns.geojson: missing (a tile made by an older treelobes): run the tile again"), std::string::npos)
            << older.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(SurveyCli, FourShardsMergeToTheBytesOfOneRun) {
    const Reference& r = reference();
    TempDir dir;
    std::vector<fs::path> shards;
    for (int i = 0; i < 4; ++i) {
        shards.push_back(dir / ("shard" + std::to_string(i)));
        ASSERT_EQ(shell(batch_command(r.tiles, shards.back(), "--shard " + std::to_string(i) + "/4") + " >/dev/null"), 0);
    }
    ASSERT_EQ(shell(merge_command({shards[3], shards[1], shards[0], shards[2]}, dir / "merged")), 0);
    expect_same_merge(r.merged, dir / "merged");
    ASSERT_EQ(shell(merge_command({shards[0], shards[1], shards[2], shards[3]}, dir / "merged_in_order")), 0);
    expect_same_merge(r.merged, dir / "merged_in_order");
    // Merging the same tile twice is refused.
    EXPECT_EQ(shell(merge_command({shards[0], shards[0]}, dir / "twice") + " 2>/dev/null"), 2);
}

TEST(SurveyCli, GnuParallelShardsMergeToTheBytesOfOneRun) {
    const Reference& r = reference();
    TempDir dir;
    const std::string command = "parallel -j2 " + cli() + " --log-level warn batch '" + r.tiles.string() + "' --out '" +
                                (dir / "batch").string() + "' --shard {}/4 " + kTileOptions + " ::: 0 1 2 3 >/dev/null";
    ASSERT_EQ(shell(command), 0) << command;
    ASSERT_EQ(shell(merge_command({dir / "batch"}, dir / "merged")), 0);
    expect_same_merge(r.merged, dir / "merged");
}

TEST(SurveyCli, KilledBatchResumesWithoutRedoingATile) {
    const Reference& r = reference();
    TempDir dir;
    const fs::path out = dir / "batch";
    // kill -9 at a random moment of the time an uninterrupted run takes.
    std::mt19937 random(std::random_device{}());
    const double moment = std::uniform_real_distribution<double>(0.05, 0.95)(random) * r.batch_seconds;
    const std::string command = "exec " + batch_command(r.tiles, out) + " >/dev/null 2>&1";
    const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
    pid_t pid = 0;
    ASSERT_EQ(posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ), 0);
    std::this_thread::sleep_for(std::chrono::duration<double>(moment));
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);

    std::map<std::string, fs::file_time_type> finished;
    if (fs::exists(out))
        for (const auto& entry : fs::directory_iterator(out))
            if (fs::exists(entry.path() / survey::kCompletionMarker))
                finished[entry.path().filename().string()] = fs::last_write_time(entry.path() / survey::kCompletionMarker);
    TempDir scratch;
    ASSERT_EQ(shell(batch_command(r.tiles, out, "", "--json") + " >'" + (scratch / "summary.json").string() + "'"), 0)
            << "killed after " << moment << " s";
    const auto summary = nlohmann::json::parse(file_bytes(scratch / "summary.json"));
    EXPECT_EQ(summary["tiles_skipped"].get<std::size_t>(), finished.size()) << "killed after " << moment << " s";
    EXPECT_EQ(summary["tiles_done"].get<std::size_t>(), kTiles - finished.size());
    for (const auto& [name, time] : finished)
        EXPECT_EQ(fs::last_write_time(out / name / survey::kCompletionMarker), time) << name << " redone";
    ASSERT_EQ(shell(merge_command({out}, dir / "merged")), 0);
    expect_same_merge(r.merged, dir / "merged");
}

// With their own airborne segmentation the tiles of one survey draw their canopy height models
// from one return spacing, measured on the tile of median density (each tile's own estimate
// differs by a few per cent, and crowns at the tile edges would differ from the uncut run's), or
// from the one given; a single `tile` run estimates its own.
TEST(SurveyCli, EveryTileDrawsItsCanopyModelFromOneReturnSpacing) {
    const Reference& r = reference();
    TempDir dir;
    const std::string own = " --mode als --min-tree-points 100000000 --map-size 200";
    const auto tile_spacings = [&](const fs::path& out) {
        std::vector<double> spacings;
        for (int i = 0; i < kTiles; ++i)
            spacings.push_back(nlohmann::json::parse(
                    file_bytes(out / ("t_" + std::to_string(i)) / "summary.json"))["options"]["chm"]["return_spacing_m"]);
        return spacings;
    };
    const auto batch = [&](const std::string& name, const std::string& extra) {
        return shell(cli() + " --log-level warn --json batch '" + r.tiles.string() + "' --out '" + (dir / name).string() + "'" + own +
                     extra + " >'" + (dir / (name + ".json")).string() + "'");
    };
    ASSERT_EQ(batch("measured", ""), 0);
    const auto summary = nlohmann::json::parse(file_bytes(dir / "measured.json"));
    const double survey = summary["return_spacing"]["metres"];
    EXPECT_GT(survey, 0.1);
    EXPECT_LT(survey, 0.5);  // 20 pulses per m^2
    EXPECT_EQ(summary["return_spacing"]["measured_on"].get<std::string>().rfind(r.tiles.string(), 0), 0u);
    for (const double spacing : tile_spacings(dir / "measured")) EXPECT_NEAR(spacing, survey, 5e-4);

    ASSERT_EQ(batch("given", " --return-spacing 0.8"), 0);
    EXPECT_TRUE(nlohmann::json::parse(file_bytes(dir / "given.json"))["return_spacing"].is_null());
    for (const double spacing : tile_spacings(dir / "given")) EXPECT_NEAR(spacing, 0.8, 1e-6);

    std::vector<double> alone;
    for (int i = 0; i < 2; ++i) {
        const fs::path out = dir / ("alone_" + std::to_string(i));
        ASSERT_EQ(shell(cli() + " --log-level warn tile '" + (r.tiles / ("t_" + std::to_string(i) + ".las")).string() + "' --out '" +
                        out.string() + "'" + own + " >/dev/null"),
                  0);
        alone.push_back(nlohmann::json::parse(file_bytes(out / "summary.json"))["options"]["chm"]["return_spacing_m"]);
    }
    EXPECT_NE(alone[0], alone[1]);
}

TEST(SurveyCli, ABadTileIsListedAndTheOthersFinish) {
    const Reference& r = reference();
    TempDir dir;
    fs::create_directories(dir / "tiles");
    for (const auto& entry : fs::directory_iterator(r.tiles)) fs::copy_file(entry.path(), dir / "tiles" / entry.path().filename());
    write_text(dir / "tiles" / "t_1b.las", "LASF but not really a LAS file");
    EXPECT_EQ(shell(batch_command(dir / "tiles", dir / "batch") + " >/dev/null 2>&1"), 3);
    const std::string failures = file_bytes(dir / "batch" / "failures.jsonl");
    ASSERT_EQ(std::count(failures.begin(), failures.end(), '\n'), 1) << failures;
    const auto failure = nlohmann::json::parse(failures);
    EXPECT_EQ(failure["tile"], "t_1b");
    EXPECT_EQ(failure["exit_code"], 2);
    EXPECT_FALSE(fs::exists(dir / "batch" / "t_1b" / survey::kCompletionMarker));
    EXPECT_EQ(shell(merge_command({dir / "batch"}, dir / "merged") + " 2>/dev/null"), 3);  // a tile is missing
    EXPECT_TRUE(file_bytes(dir / "merged" / "trees.csv") == file_bytes(r.merged / "trees.csv"));
    EXPECT_EQ(file_bytes(dir / "merged" / "failures.jsonl"), failures);
}

TEST(SurveyCli, TilesTooBigForTheMemoryBudgetAreRefusedBeforeLoading) {
    const Reference& r = reference();
    TempDir dir;
    EXPECT_EQ(shell(batch_command(r.tiles, dir / "batch", "--max-memory 100K") + " >/dev/null 2>&1"), 3);
    const std::string failures = file_bytes(dir / "batch" / "failures.jsonl");
    EXPECT_EQ(std::count(failures.begin(), failures.end(), '\n'), kTiles) << failures;
    EXPECT_NE(failures.find("points need about"), std::string::npos) << failures;
    EXPECT_NE(failures.find("retile"), std::string::npos) << failures;
    EXPECT_FALSE(fs::exists(dir / "batch" / "t_0" / "summary.json"));
    EXPECT_EQ(shell(cli() + " batch '" + r.tiles.string() + "' --out '" + (dir / "x").string() + "' --max-memory 12Q 2>/dev/null"), 1);
    EXPECT_EQ(shell(cli() + " batch '" + r.tiles.string() + "' --out '" + (dir / "x").string() + "' --shard 4/4 2>/dev/null"), 1);
    EXPECT_EQ(shell(cli() + " batch '" + r.tiles.string() + "' --out '" + (dir / "x").string() + "' --no-such-tile-flag 2>/dev/null"), 1);
    EXPECT_EQ(shell(cli() + " batch '" + r.tiles.string() + "' --out '" + (dir / "x").string() + "' --json 2>/dev/null"), 1);
}

TEST(SurveyCli, RetiledTilesKeepEveryPointCrsAndScale) {
    const Reference& r = reference();
    TempDir dir;
    const std::string wkt = "PROJCS[\"WGS 84 / UTM zone 32N\",AUTHORITY[\"EPSG\",\"32632\"]]";
    std::size_t points = 0;
    std::string inputs;
    for (int i = 0; i < kTiles; ++i) {
        PointCloud cloud = read_point_cloud(r.tiles / ("t_" + std::to_string(i) + ".las"));
        cloud.georef.crs_wkt = wkt;
        points += cloud.size();
        const fs::path input = dir / ("in_" + std::to_string(i) + ".las");
        write_point_cloud(cloud, input);
        inputs += " '" + input.string() + "'";
    }
    // The 80 m x 20 m row into 40 m squares: two main tiles named by their lower-left corners (and
    // small ones for the few points of the synthetic scan beyond the tile edges).
    ASSERT_EQ(shell(cli() + " --log-level warn retile" + inputs + " --size 40 --out '" + (dir / "retiled").string() + "' >/dev/null"), 0);
    EXPECT_TRUE(fs::exists(dir / "retiled" / "tile_500000_5400000.las"));
    EXPECT_TRUE(fs::exists(dir / "retiled" / "tile_500040_5400000.las"));
    std::size_t retiled_points = 0;
    for (const auto& entry : fs::directory_iterator(dir / "retiled")) {
        double x0 = 0, y0 = 0;
        ASSERT_EQ(std::sscanf(entry.path().filename().string().c_str(), "tile_%lf_%lf.las", &x0, &y0), 2) << entry.path();
        const PointCloud cloud = read_point_cloud(entry.path());
        retiled_points += cloud.size();
        EXPECT_EQ(cloud.source.version, "1.4");
        EXPECT_EQ(cloud.georef.crs_wkt, wkt);
        EXPECT_EQ(cloud.source.las_scale, read_point_cloud(dir / "in_0.las").source.las_scale);
        ASSERT_NE(cloud.extra("treeID"), nullptr);
        const auto [lo, hi] = cloud.bounds();
        EXPECT_GE(cloud.origin.x() + lo.x(), x0 - 1e-3) << entry.path();
        EXPECT_LT(cloud.origin.x() + hi.x(), x0 + 40.0 + 1e-3) << entry.path();
        EXPECT_GE(cloud.origin.y() + lo.y(), y0 - 1e-3) << entry.path();
        EXPECT_LT(cloud.origin.y() + hi.y(), y0 + 40.0 + 1e-3) << entry.path();
    }
    EXPECT_EQ(retiled_points, points);
    // Too big for the budget: refused before reading, with the estimate.
    EXPECT_EQ(shell(cli() + " retile" + inputs + " --size 40 --max-memory 1K --out '" + (dir / "no").string() + "' 2>/dev/null"), 2);
    EXPECT_FALSE(fs::exists(dir / "no"));
}
