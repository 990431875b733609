// Trees crossing tile edges: one synthetic plot cut by `retile` into 20 m squares, so that many
// crowns straddle an edge. Run with --buffer, every true tree is modelled exactly once, by the
// tile holding its stem base, and the merge equals one run on the uncut plot (same survey-wide
// ids, same trees, bases within 1 cm); run without a buffer, trees cut by an edge come out in
// pieces, one per tile. The plot's labels (--use-input-segmentation) make "the same tree" exact:
// a tree's tree_id in the tables is its true id.
#include "support/test_support.hpp"
#include "survey_fixture.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <sstream>

using namespace treelobes;
using namespace treelobes::test;
namespace fs = std::filesystem;

namespace {

constexpr double kPlotSize = 40.0, kTileSize = 20.0, kBuffer = 15.0;  // the widest synthetic crowns are ~30 m across
constexpr double kCornerX = 500000.0, kCornerY = 5400000.0;

// One CSV as rows of named cells.
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& path) {
    std::istringstream in(file_bytes(path));
    std::string line;
    std::getline(in, line);
    std::vector<std::string> header;
    for (std::istringstream cells(line); std::getline(cells, line, ',');) header.push_back(line);
    std::vector<std::map<std::string, std::string>> rows;
    for (std::string row; std::getline(in, row);) {
        if (row.empty()) continue;
        std::map<std::string, std::string> named;
        std::istringstream cells(row);
        for (const std::string& name : header) {
            std::string cell;
            std::getline(cells, cell, ',');
            named[name] = cell;
        }
        rows.push_back(std::move(named));
    }
    return rows;
}

double number(const std::map<std::string, std::string>& row, const std::string& column) { return std::stod(row.at(column)); }

struct Plot {
    TempDir dir;
    fs::path tiles, truth, single;
};

// The plot, its retiled squares and one run on the uncut plot, made once for the suite (and its
// folder removed when the process ends).
const Plot& plot() {
    static const std::unique_ptr<Plot> made = [] {
        auto p = std::make_unique<Plot>();
        const std::string synth = cli() + " --log-level warn synth tile --trees 24 --size " + std::to_string(kPlotSize) +
                                  " --seed 7 --pulse-density 20 --max-leaves 2000 --origin 500000 5400000 300 --out '" +
                                  (p->dir / "plot").string() + "' >/dev/null";
        EXPECT_EQ(shell(synth), 0) << synth;
        p->truth = p->dir / "plot" / "truth.csv";
        p->tiles = p->dir / "tiles";
        EXPECT_EQ(shell(cli() + " --log-level warn retile '" + (p->dir / "plot" / "tile.las").string() + "' --size " +
                        std::to_string(kTileSize) + " --out '" + p->tiles.string() + "' >/dev/null"),
                  0);
        EXPECT_EQ(shell(cli() + " --log-level error tile '" + (p->dir / "plot" / "tile.las").string() + "' --out '" +
                        (p->dir / "single").string() + "' " + kTileOptions + " >/dev/null"),
                  0);
        p->single = p->dir / "single_merged";
        EXPECT_EQ(shell(cli() + " --log-level error merge '" + (p->dir / "single").string() + "' --out '" + p->single.string() +
                        "' >/dev/null"),
                  0);
        return p;
    }();
    return *made;
}

// Batch over the squares (all shards, one after the other) and merge; returns the merge folder.
fs::path batch_and_merge(const fs::path& dir, const std::string& options, int shards = 1) {
    for (int i = 0; i < shards; ++i) {
        const std::string shard = shards > 1 ? " --shard " + std::to_string(i) + "/" + std::to_string(shards) : "";
        shell(cli() + " --log-level error batch '" + plot().tiles.string() + "' --out '" + (dir / "batch").string() + "'" + shard + " " +
              options + " " + kTileOptions + " >/dev/null");
    }
    shell(cli() + " --log-level error merge '" + (dir / "batch").string() + "' --out '" + (dir / "merged").string() + "' >/dev/null");
    return dir / "merged";
}

const std::string& buffer_options() {
    static const std::string options = "--buffer " + std::to_string(kBuffer) + " --tile-size " + std::to_string(kTileSize);
    return options;
}

// The squares run with the buffer and merged, made once for the suite.
const fs::path& buffered_merge() {
    static TempDir dir;
    static const fs::path merged = batch_and_merge(dir.path(), buffer_options());
    return merged;
}

std::map<std::string, int> rows_per_true_tree(const std::vector<std::map<std::string, std::string>>& rows) {
    std::map<std::string, int> count;
    for (const auto& row : rows) ++count[row.at("tree_id")];
    return count;
}

}  // namespace

TEST(SurveyBuffer, ThePlotHasTreesAcrossTheTileEdges) {
    int straddling = 0;
    for (const auto& tree : read_csv(plot().truth)) {
        const double reach = number(tree, "crown_diameter_m") / 2;
        const double x = number(tree, "x"), y = number(tree, "y");
        if (std::abs(x - (kCornerX + kTileSize)) < reach || std::abs(y - (kCornerY + kTileSize)) < reach) ++straddling;
    }
    EXPECT_GE(straddling, 6);
}

TEST(SurveyBuffer, EveryTreeOnceAndAsInOneRunOfTheUncutPlot) {
    const fs::path& merged = buffered_merge();
    const auto rows = read_csv(merged / "trees.csv");
    const auto single = read_csv(plot().single / "trees.csv");
    ASSERT_GE(single.size(), 20u);  // 24 trees, a few may be too small to model
    ASSERT_EQ(rows.size(), single.size());

    // Each true tree once (with the plot's labels, tree_id is the true id).
    for (const auto& [tree, count] : rows_per_true_tree(rows)) EXPECT_EQ(count, 1) << "true tree " << tree;

    // The same survey-wide ids as the uncut plot, bases within 1 cm, each under its true crown.
    std::map<std::string, std::map<std::string, std::string>> truth;
    for (auto& tree : read_csv(plot().truth)) truth[tree.at("tree_id")] = tree;
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const auto &a = rows[i], &b = single[i];  // both sorted by survey-wide id
        EXPECT_EQ(a.at("global_id"), b.at("global_id"));
        EXPECT_EQ(a.at("tree_id"), b.at("tree_id"));
        for (const char* axis : {"x", "y", "z"}) EXPECT_NEAR(number(a, axis), number(b, axis), 0.01) << a.at("global_id") << " " << axis;
        EXPECT_EQ(a.at("points"), b.at("points")) << a.at("global_id") << ": the tree is not whole";
        const auto& t = truth.at(a.at("tree_id"));
        // A stem base estimated from an airborne scan lies under the tree's crown (the highest
        // point when the stem is not seen), not always on the stem.
        EXPECT_LE(std::hypot(number(a, "x") - number(t, "x"), number(a, "y") - number(t, "y")), number(t, "crown_diameter_m") / 2 + 0.5)
                << "true tree " << a.at("tree_id");
        // The tree is the one of the tile whose square holds its segmentation base: the point its
        // survey-wide id names ("<x>_<y>" of the base's 1 cm cell; x, y are the stem position measured).
        const std::string& id = a.at("global_id");
        const double base_x = std::stod(id.substr(0, id.find('_'))), base_y = std::stod(id.substr(id.find('_') + 1));
        char tile[64];
        std::snprintf(tile, sizeof tile, "tile_%.0f_%.0f", std::floor(base_x / kTileSize) * kTileSize,
                      std::floor(base_y / kTileSize) * kTileSize);
        EXPECT_EQ(a.at("tile"), tile) << a.at("global_id");
    }
    const auto summary = nlohmann::json::parse(file_bytes(merged / "summary.json"));
    EXPECT_EQ(summary["trees_in_several_tiles"], 0);
    EXPECT_GT(summary["counts"]["trees_in_buffer"].get<int>(), 0);  // the neighbours' trees each tile saw and left

    // Shards find the same neighbours (every tile of the batch) and merge to the same bytes.
    TempDir sharded;
    expect_same_merge(merged, batch_and_merge(sharded.path(), buffer_options(), 4));
}

TEST(SurveyBuffer, WithoutABufferTreesAcrossEdgesComeOutInPieces) {
    TempDir dir;
    const auto pieces = rows_per_true_tree(read_csv(batch_and_merge(dir.path(), "") / "trees.csv"));
    const auto whole = rows_per_true_tree(read_csv(buffered_merge() / "trees.csv"));
    int cut = 0, extra_rows = 0;
    for (const auto& [tree, count] : pieces)
        if (count > 1) {
            ++cut;
            extra_rows += count - 1;
        }
    int cut_with_buffer = 0;
    for (const auto& [tree, count] : whole) cut_with_buffer += count > 1;
    EXPECT_GE(cut, 4) << "trees modelled in pieces by several tiles";
    EXPECT_EQ(cut_with_buffer, 0);
    EXPECT_GT(extra_rows, 0);
    std::printf("without a buffer: %d true trees in %d pieces too many; with a %.0f m buffer: %d\n", cut, extra_rows, kBuffer,
                cut_with_buffer);
}

// Every tile's summary names the kept trees that reach its buffer's outer edge (buffer.trees_at_edge).
std::set<std::string> trees_named_at_buffer_edge(const fs::path& batch) {
    std::set<std::string> named;
    for (const auto& tile : fs::directory_iterator(batch)) {
        if (!fs::exists(tile.path() / "summary.json")) continue;
        const auto summary = nlohmann::json::parse(file_bytes(tile.path() / "summary.json"));
        for (const auto& id : summary["buffer"]["trees_at_edge"]) named.insert(id.get<std::string>());
    }
    return named;
}

// A tree that goes on beyond the buffer is cut there. A 3 m buffer cuts several: the tiles name
// the trees that reach their buffer's outer edge, and every tree that comes out otherwise than
// from the uncut plot is among them. The 15 m buffer of the other tests cuts none and names none.
TEST(SurveyBuffer, TreesReachingTheBufferEdgeAreNamed) {
    TempDir dir;
    const fs::path merged = batch_and_merge(dir.path(), "--buffer 3 --tile-size " + std::to_string(kTileSize));
    const std::set<std::string> named = trees_named_at_buffer_edge(dir / "batch");
    std::map<std::string, std::string> whole_points;
    for (const auto& row : read_csv(plot().single / "trees.csv")) whole_points[row.at("global_id")] = row.at("points");
    int cut = 0;
    for (const auto& row : read_csv(merged / "trees.csv")) {
        const auto whole = whole_points.find(row.at("global_id"));
        if (whole != whole_points.end() && whole->second == row.at("points")) continue;
        ++cut;
        EXPECT_TRUE(named.count(row.at("global_id"))) << row.at("global_id") << " was cut by the buffer's edge and not named";
    }
    EXPECT_GT(cut, 0);
    EXPECT_GE(named.size(), static_cast<std::size_t>(cut));
    // The merge gathers them in one list.
    const auto summary = nlohmann::json::parse(file_bytes(merged / "summary.json"));
    EXPECT_EQ(summary["trees_at_buffer_edge"].get<std::vector<std::string>>(), std::vector<std::string>(named.begin(), named.end()));
    buffered_merge();
    EXPECT_TRUE(trees_named_at_buffer_edge(buffered_merge().parent_path() / "batch").empty());
    EXPECT_TRUE(nlohmann::json::parse(file_bytes(buffered_merge() / "summary.json"))["trees_at_buffer_edge"].empty());
}
