// `render --color species` (legend, one colour per species name) on clouds with a species
// attribute and on tile output folders, and `render --contact-sheet`: one labelled panel per
// tree, sorted by id, each tree filling its panel.
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "render/colour_map.hpp"
#include "render/image.hpp"
#include "render/text.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <iterator>
#include <iomanip>
#include <map>
#include <memory>
#include <set>
#include <sstream>

using namespace treelobes;
using namespace treelobes::render;
namespace fs = std::filesystem;

namespace {

// Library ids of config/species.yaml (stable by contract): their colours are id_colour(id).
const std::map<std::string, int> library_ids = {{"lagerstroemia", 4}, {"ailanthus_altissima", 5}, {"palm", 6}, {"pine", 8}, {"birch", 11}};
constexpr Rgba white{255, 255, 255, 255}, label_grey{235, 235, 235, 255}, no_species{170, 170, 170, 255};

std::map<Rgba, std::size_t> colour_counts(const Image& image, int x0, int x1) {
    std::map<Rgba, std::size_t> counts;
    for (int y = 0; y < image.height; ++y)
        for (int x = x0; x < x1; ++x) ++counts[image.at(x, y)];
    return counts;
}

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream stream(line);
    for (std::string cell; std::getline(stream, cell, ',');) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
}

// One `treelobes tile` run on the committed synthetic tile (every segment modelled), shared by
// the tests of the process, plus a copy whose trees.csv names species (what `tile --model`
// writes in that column): tree i gets species_of(i). Prepared in SetUp, so a failure fails the
// test (a failing SetUpTestSuite only marks the tests skipped).
class RenderTile : public ::testing::Test {
protected:
    void SetUp() override {
        if (!dir_) {
            dir_ = std::make_unique<test::TempDir>();
            prepared_ = prepare();
        }
        ASSERT_TRUE(prepared_) << "could not run `treelobes tile` on the synthetic tile";
    }
    static bool prepare() {
        const auto r = test::run_cli("--log-level error tile " + test::quoted(test::source_dir() / "data/synthetic/tile/tile.las") +
                                     " --min-tree-points 30 --out " + test::quoted(*dir_ / "plain"));
        EXPECT_EQ(r.exit_code, 0) << r.err;
        if (r.exit_code != 0) return false;
        fs::copy(*dir_ / "plain", *dir_ / "species", fs::copy_options::recursive);
        std::ifstream in(*dir_ / "plain" / "trees.csv");
        std::string line, csv;
        std::getline(in, line);
        csv = line + "\n";
        const auto header = split(line);
        const std::size_t species = std::find(header.begin(), header.end(), "species") - header.begin();
        const std::size_t id = std::find(header.begin(), header.end(), "tree_id") - header.begin();
        if (species >= header.size() || id >= header.size()) return false;
        while (std::getline(in, line)) {
            auto cells = split(line);
            cells[species] = species_of(std::stoi(cells[id]));
            for (std::size_t i = 0; i < cells.size(); ++i) csv += (i ? "," : "") + cells[i];
            csv += "\n";
        }
        test::write_text(*dir_ / "species" / "trees.csv", csv);
        return true;
    }
    static std::string species_of(int tree_id) { return std::vector<std::string>{"pine", "birch", "palm"}[tree_id % 3]; }
    static fs::path path(const std::string& name) { return *dir_ / name; }
    static std::unique_ptr<test::TempDir> dir_;  // removed at exit
    static bool prepared_;
};
std::unique_ptr<test::TempDir> RenderTile::dir_;
bool RenderTile::prepared_ = false;

// Width over height of the tile's points seen from above: the top view's panel shape.
double top_aspect(const fs::path& cloud_file) {
    const PointCloud cloud = read_point_cloud(cloud_file);
    Eigen::Vector3f lo = cloud.positions.front(), hi = lo;
    for (const auto& p : cloud.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    return (hi.x() - lo.x()) / (hi.y() - lo.y());
}

}  // namespace

TEST_F(RenderTile, SpeciesOfACloudAttributeWithLegend) {
    const auto tile = test::source_dir() / "data" / "synthetic" / "tile" / "tile.las";
    const auto r =
            test::run_cli("render " + test::quoted(tile) + " --view top --color species --size 240 --out " + test::quoted(path("sp.png")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Image image = read_png(path("sp.png"));
    const int panel = static_cast<int>(std::lround(240 * top_aspect(tile)));  // the panel takes the tile's shape
    ASSERT_GT(image.width, panel + 40) << "no legend beside the panel";
    const auto points = colour_counts(image, 0, panel - 4), legend = colour_counts(image, panel + 4, image.width);
    // The tile's five species (truth.csv) each in its library colour, in the points and in the legend.
    for (const auto& [name, id] : library_ids) {
        EXPECT_GT(points.count(id_colour(id)) ? points.at(id_colour(id)) : 0, 50u) << name;
        EXPECT_GT(legend.count(id_colour(id)) ? legend.at(id_colour(id)) : 0, 20u) << name << " has no legend swatch";
    }
    EXPECT_GT(points.at(no_species), 1000u);  // ground and understory
    // The same species keeps its colour in another picture: birch_3 alone.
    const auto birch = test::run_cli("render " + test::quoted(test::source_dir() / "data/synthetic/birch_3.las") +
                                     " --color species --size 200 --out " + test::quoted(path("birch.png")));
    ASSERT_EQ(birch.exit_code, 0) << birch.err;
    const auto birch_colours = colour_counts(read_png(path("birch.png")), 0, 100);
    EXPECT_GT(birch_colours.count(id_colour(11)) ? birch_colours.at(id_colour(11)) : 0, 100u);
    EXPECT_EQ(birch_colours.count(id_colour(8)), 0u);  // no pine in a birch
    // A cloud without a species attribute: one line, exit 2.
    test::write_text(path("bare.xyz"), "0 0 0\n1 1 1\n0 1 2\n");
    const auto bare = test::run_cli("render " + test::quoted(path("bare.xyz")) + " --color species --out " + test::quoted(path("x.png")));
    EXPECT_EQ(bare.exit_code, 2);
    EXPECT_NE(bare.err.find("species attribute"), std::string::npos) << bare.err;
}

TEST_F(RenderTile, SpeciesOfATileOutputFolder) {
    auto r = test::run_cli("render " + test::quoted(path("species")) + " --view top --color species --size 240 --json --out " +
                           test::quoted(path("tile_sp.png")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("\"species\": 3"), std::string::npos) << r.out;
    const int panel = static_cast<int>(std::lround(240 * top_aspect(path("species") / "points.las")));
    const auto counts = colour_counts(read_png(path("tile_sp.png")), 0, panel - 4);
    for (const char* name : {"pine", "birch", "palm"})
        EXPECT_GT(counts.count(id_colour(library_ids.at(name))) ? counts.at(id_colour(library_ids.at(name))) : 0, 200u) << name;
    EXPECT_EQ(counts.count(id_colour(library_ids.at("lagerstroemia"))), 0u);  // trees.csv wins over the points' own attribute
    r = test::run_cli("render " + test::quoted(path("plain")) + " --color species --out " + test::quoted(path("x.png")));
    EXPECT_EQ(r.exit_code, 2);  // a tile run without --model names no species
    EXPECT_NE(r.err.find("--model"), std::string::npos) << r.err;
}

TEST_F(RenderTile, ContactSheetOnePanelPerTreeSortedAndLabelled) {
    const std::string command =
            "render " + test::quoted(path("species")) + " --contact-sheet --view front --color species --size 160 --json --out ";
    auto r = test::run_cli(command + test::quoted(path("sheet.png")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream rows(path("species") / "trees.csv");
    const long tree_count = std::count(std::istreambuf_iterator<char>(rows), std::istreambuf_iterator<char>(), '\n') - 1;
    ASSERT_GT(tree_count, 10);
    EXPECT_EQ(nlohmann::json::parse(r.out)["trees"], tree_count) << r.out;
    const Image sheet = read_png(path("sheet.png"));
    // Layout at --size 160: font scale 1, gap 2, label strip 9 px, then the 160 px panel.
    const int gap = 2, label = 9, height = 160;
    int width = 0;
    while (sheet.at(gap + width, gap) == label_grey) ++width;
    ASSERT_GT(width, 40);
    const int columns = (sheet.width - gap) / (width + gap);  // the legend is narrower than a panel
    ASSERT_GE(columns, 2);
    std::ifstream in(path("species") / "trees.csv");
    std::string line;
    std::getline(in, line);
    const auto header = split(line);
    const std::size_t height_column = std::find(header.begin(), header.end(), "height_m") - header.begin();
    const std::size_t id_column = std::find(header.begin(), header.end(), "tree_id") - header.begin();
    ASSERT_LT(id_column, header.size());
    for (int k = 0; std::getline(in, line); ++k) {
        const auto cells = split(line);
        const int id = std::stoi(cells[id_column]);
        ASSERT_EQ(id, k + 1) << "trees.csv of the fixture lists ids 1..N in order (every segment modelled)";
        const int x0 = gap + (k % columns) * (width + gap), y0 = gap + (k / columns) * (height + label + gap);
        // The label strip reads "ID <id>  <species>  <height> M", drawn with the project's font.
        std::ostringstream text;
        text << "ID " << id << "  " << species_of(id) << "  " << std::fixed << std::setprecision(1) << std::stod(cells[height_column])
             << " M";
        Image expected(width, label, label_grey);
        draw_text(expected, 2, 2, text.str(), 1, {20, 20, 20, 255});
        for (int y = 0; y < label; ++y)
            for (int x = 0; x < width; ++x)
                ASSERT_EQ(sheet.at(x0 + x, y0 + y), expected.at(x, y)) << "label of tree " << id << " at " << x << "," << y;
        // The tree fills its panel: its points reach within 8 % of two opposite borders.
        int left = width, right = -1, top = height, bottom = -1;
        std::set<Rgba> colours;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const Rgba c = sheet.at(x0 + x, y0 + label + y);
                if (c == white) continue;
                left = std::min(left, x), right = std::max(right, x), top = std::min(top, y), bottom = std::max(bottom, y);
                colours.insert(c);
            }
        const bool fills_height = top <= height * 0.08 && bottom >= height * 0.92;
        const bool fills_width = left <= width * 0.08 && right >= width * 0.92;
        EXPECT_TRUE(fills_height || fills_width)
                << "tree " << id << " spans x " << left << ".." << right << ", y " << top << ".." << bottom;
        EXPECT_EQ(colours, std::set<Rgba>{id_colour(library_ids.at(species_of(id)))})
                << "tree " << id << " drawn in its species colour only";
    }
    // Deterministic.
    r = test::run_cli(command + test::quoted(path("sheet2.png")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(read_file(path("sheet.png")), read_file(path("sheet2.png")));
    // Not a tile output folder: exit 2.
    r = test::run_cli("render " + test::quoted(test::source_dir() / "data/synthetic/birch_3.las") + " --contact-sheet --out " +
                      test::quoted(path("x.png")));
    EXPECT_EQ(r.exit_code, 2) << r.err;
}
