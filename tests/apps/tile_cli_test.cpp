// End-to-end: `treelobes tile` on a small synthetic tile (outputs present and consistent with
// each other, the labelled LAS, resume and --overwrite, byte-identical re-runs, trees too small
// for a model measured only, failures.jsonl with exit 3, buildings left out) and on bad tiles (empty, all ground, one
// tree, no CRS, NaN coordinates, an unclassified building, a CRS in feet known only by its code).
#include "core/cloud_io.hpp"
#include "core/skeleton_io.hpp"
#include "encode/forest_file.hpp"
#include "forestry/measures.hpp"
#include "lobes/tlobe_io.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

using namespace treelobes;
using test::quoted;
using test::run_cli;
using test::TempDir;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);)
        if (!line.empty()) lines.push_back(line);
    return lines;
}

const std::string kWkt = "PROJCS[\"WGS 84 / UTM zone 32N\",AUTHORITY[\"EPSG\",\"32632\"]]";

// A small airborne tile with truth labels (treeID), made once for the whole suite, with a CRS
// added so that its passing through can be checked.
const fs::path& small_tile() {
    static TempDir dir;
    static const fs::path tile = [] {
        const auto r =
                run_cli("--log-level warn synth tile --trees 5 --size 20 --seed 11 --pulse-density 20 --max-leaves 2000 "
                        "--species pine birch --origin 500000 5400000 300 --out " +
                        quoted(dir / "synth"));
        EXPECT_EQ(r.exit_code, 0) << r.err;
        PointCloud cloud = read_point_cloud(dir / "synth" / "tile.las");
        cloud.georef.crs_wkt = kWkt;
        write_point_cloud(cloud, dir / "tile.las");
        return dir / "tile.las";
    }();
    return tile;
}

std::string run_tile(const fs::path& out, const std::string& extra = "--use-input-segmentation") {
    return "tile " + quoted(small_tile()) + " --out " + quoted(out) + " " + extra;
}

}  // namespace

TEST(TileCli, OutputsArePresentAndConsistent) {
    TempDir dir;
    const auto r = run_cli("--json " + run_tile(dir / "out"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary, nlohmann::json::parse(slurp(dir / "out" / "summary.json")));
    const int trees = summary["counts"]["trees"].get<int>();
    EXPECT_EQ(trees, 5);
    for (const char* key : {"read", "terrain", "segmentation", "trees", "outputs", "total"})
        EXPECT_TRUE(summary["seconds"].contains(key)) << key;
    EXPECT_GT(summary["peak_memory_mb"].get<double>(), 0.0);
    EXPECT_EQ(summary["options"]["mode_used"], "input");
    EXPECT_FALSE(fs::exists(dir / "out" / "failures.jsonl"));

    // One row, one feature, one forest tree and one set of files per tree.
    const auto csv = lines_of(slurp(dir / "out" / "trees.csv"));
    ASSERT_EQ(csv.size(), static_cast<std::size_t>(trees + 1));
    EXPECT_EQ(csv[0].rfind("global_id,tree_id,x,y,z,height_m,dbh_m,dbh_quality,stems,", 0), 0u);
    const auto geojson = nlohmann::json::parse(slurp(dir / "out" / "trees.geojson"));
    ASSERT_EQ(geojson["features"].size(), static_cast<std::size_t>(trees));
    EXPECT_EQ(geojson["crs_wkt"], kWkt);
    encode::ForestReader forest(dir / "out" / "tile.forest");
    EXPECT_EQ(forest.size(), static_cast<std::size_t>(trees));
    std::set<std::string> global_ids;  // survey-wide ids from the stem base: "<x>_<y>" of its 1 cm cell
    for (const auto& feature : geojson["features"]) {
        const std::string global_id = feature["properties"]["global_id"].get<std::string>();
        EXPECT_EQ(global_id.rfind("5000", 0), 0u) << global_id;
        EXPECT_TRUE(global_ids.insert(global_id).second) << global_id;
        char stem[32];
        std::snprintf(stem, sizeof stem, "tree_%04d", feature["properties"]["tree_id"].get<int>());
        for (const std::string suffix : {"_skeleton.ply", "_branches.ply", ".tlobe", ".dbf6", ".json"})
            EXPECT_TRUE(fs::exists(dir / "out" / "trees" / (stem + suffix))) << stem << suffix;
        // Coordinates in the tile's frame (the synthetic origin), heights plausible.
        const auto xyz = feature["geometry"]["coordinates"];
        EXPECT_GT(xyz[0].get<double>(), 500000.0);
        EXPECT_LT(xyz[0].get<double>(), 500020.0);
        EXPECT_GT(xyz[1].get<double>(), 5400000.0);
        EXPECT_GT(feature["properties"]["height_m"].get<double>(), 2.0);
        EXPECT_TRUE(feature["properties"]["dbh_quality"].is_string());
        const bool measured = feature["properties"]["dbh_quality"] != "not_visible";
        EXPECT_EQ(feature["properties"]["stems"].is_number_integer(), measured);  // trunks the DBH covers, null when none
    }
    for (const char* file : {"dtm.asc", "hillshade.png", "top_view.png", "points.las"}) EXPECT_TRUE(fs::exists(dir / "out" / file)) << file;

    // The crowns: the same features with each crown's outline, a closed counter-clockwise ring
    // (RFC 7946) whose area is the tree's crown_area_m2.
    const auto crowns = nlohmann::json::parse(slurp(dir / "out" / "crowns.geojson"));
    EXPECT_EQ(crowns["crs_wkt"], kWkt);
    ASSERT_EQ(crowns["features"].size(), geojson["features"].size());
    for (std::size_t f = 0; f < crowns["features"].size(); ++f) {
        const auto& crown = crowns["features"][f];
        EXPECT_EQ(crown["properties"], geojson["features"][f]["properties"]);
        ASSERT_EQ(crown["geometry"]["type"], "Polygon");
        const auto ring = crown["geometry"]["coordinates"][0];
        ASSERT_GE(ring.size(), 4u);
        EXPECT_EQ(ring.front(), ring.back());
        double twice_signed_area = 0.0;
        for (std::size_t i = 1; i < ring.size(); ++i) {
            const double x0 = ring[i - 1][0].get<double>() - 500000.0, y0 = ring[i - 1][1].get<double>() - 5400000.0;
            const double x1 = ring[i][0].get<double>() - 500000.0, y1 = ring[i][1].get<double>() - 5400000.0;
            twice_signed_area += x0 * y1 - x1 * y0;
            EXPECT_GT(x1, -1.0);
            EXPECT_LT(x1, 21.0);
        }
        EXPECT_NEAR(twice_signed_area / 2.0, crown["properties"]["crown_area_m2"].get<double>(), 0.05);
    }

    // The labelled points: treeID (int32), ground class 2, heights; scale/offset and CRS kept.
    const PointCloud input = read_point_cloud(small_tile());
    const PointCloud points = read_point_cloud(dir / "out" / "points.las");
    ASSERT_EQ(points.size(), input.size());
    const ExtraAttribute* ids = points.extra("treeID");
    ASSERT_NE(ids, nullptr);
    EXPECT_EQ(ids->type, AttributeType::Int32);
    EXPECT_EQ(ids->values, input.extra("treeID")->values);  // taken as they are
    ASSERT_NE(points.extra("HeightAboveGround"), nullptr);
    ASSERT_EQ(points.classification.size(), points.size());
    std::size_t ground = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        ground += points.classification[i] == 2;
        if (points.classification[i] == 2) {
            EXPECT_LT(std::abs(points.extra("HeightAboveGround")->values[i]), 0.5);
        }
    }
    EXPECT_GT(ground, points.size() / 10);
    EXPECT_EQ(points.georef.crs_wkt, kWkt);
    EXPECT_EQ(points.source.las_scale, input.source.las_scale);
    EXPECT_EQ(points.source.las_offset, input.source.las_offset);
    EXPECT_NEAR((points.global(0) - input.global(0)).norm(), 0.0, 1e-3);
}

// An airborne scan shows crowns, not stems: each tree's skeleton is joined to the ground at its
// stem position, so the model stands there and its stem counts in the woody volume (before, the
// skeleton began at the crown's base and the volume was a median 0.06 of the true one on the
// demo tile, docs/tile.md).
TEST(TileCli, AirborneTreesStandOnTheGroundAndTheirStemsCountInTheWoodyVolume) {
    TempDir dir;
    const auto r = run_cli(run_tile(dir / "out"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const fs::path synth = small_tile().parent_path() / "synth";
    // Truth: stem positions (truth.csv: tree_id,species,species_id,seed,x,y,z,...) and skeletons.
    std::vector<std::pair<Eigen::Vector2d, double>> truth;  // stem position, true woody volume
    const auto truth_rows = lines_of(slurp(synth / "truth.csv"));
    for (std::size_t i = 1; i < truth_rows.size(); ++i) {
        std::vector<std::string> cells;
        std::istringstream row(truth_rows[i]);
        for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
        const TreeGraph skeleton = read_skeleton_ply(synth / "skeletons" / ("tree_" + cells[0] + ".ply"));
        truth.emplace_back(Eigen::Vector2d(std::stod(cells[4]), std::stod(cells[5])), forestry::woody_volume(skeleton));
    }
    const auto geojson = nlohmann::json::parse(slurp(dir / "out" / "trees.geojson"));
    std::vector<double> ratios;
    for (const auto& feature : geojson["features"]) {
        const auto& properties = feature["properties"];
        EXPECT_EQ(properties["dbh_quality"], "not_visible");
        char stem[32];
        std::snprintf(stem, sizeof stem, "tree_%04d_skeleton.ply", properties["tree_id"].get<int>());
        const TreeGraph skeleton = read_skeleton_ply(dir / "out" / "trees" / stem);
        const Eigen::Vector3d root = skeleton.origin + skeleton.nodes[0].position.cast<double>();
        const auto xyz = feature["geometry"]["coordinates"];
        const Eigen::Vector3d position(xyz[0].get<double>(), xyz[1].get<double>(), xyz[2].get<double>());
        EXPECT_LT((root - position).norm(), 0.01) << stem;  // on the ground at the stem
        const auto nearest = std::min_element(truth.begin(), truth.end(), [&](const auto& a, const auto& b) {
            return (a.first - position.head<2>()).norm() < (b.first - position.head<2>()).norm();
        });
        ratios.push_back(properties["woody_volume_m3"].get<double>() / nearest->second);
    }
    ASSERT_EQ(ratios.size(), 5u);
    std::sort(ratios.begin(), ratios.end());
    EXPECT_GT(ratios[2], 0.5);  // the median: a guessed stem (height / 50 at its foot), not a measured one
    EXPECT_LT(ratios[2], 2.0);
}

// A classified survey's buildings (and water, wires, noise) are no tree's: the points of one tree
// of the small tile classified as a building (6) are left out of the fresh segmentation, and the
// summary and one line on stderr count them.
TEST(TileCli, PointsClassifiedAsBuildingsAreNoTrees) {
    TempDir dir;
    PointCloud cloud = read_point_cloud(small_tile());
    const ExtraAttribute* truth = cloud.extra("treeID");
    ASSERT_NE(truth, nullptr);
    ASSERT_EQ(cloud.classification.size(), cloud.size());
    std::size_t building = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (truth->values[i] == 1) {
            cloud.classification[i] = 6;
            ++building;
        }
    ASSERT_GT(building, 100u);
    write_point_cloud(cloud, dir / "tile.las");
    const auto r = run_cli("--json tile " + quoted(dir / "tile.las") + " --mode als --out " + quoted(dir / "o"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["counts"]["left_out_by_class"]["building"], building);
    EXPECT_NE(r.err.find("left out of the trees by their class: " + std::to_string(building) + " building (6)"), std::string::npos)
            << r.err;
    const PointCloud labelled = read_point_cloud(dir / "o" / "points.las");
    const ExtraAttribute* found = labelled.extra("treeID");
    ASSERT_NE(found, nullptr);
    std::size_t building_in_trees = 0;
    for (std::size_t i = 0; i < labelled.size(); ++i) building_in_trees += labelled.classification[i] == 6 && found->values[i] != 0;
    EXPECT_EQ(building_in_trees, 0u);
    EXPECT_EQ(std::count(labelled.classification.begin(), labelled.classification.end(), 6), static_cast<long>(building));
}

// --budget-kb bounds every tree's .tlobe (2.0-3.8 kB at the default 39 kB on this tile): the
// encoder coarsens the occupancy and simplifies the lobes until each fits 2 kB.
TEST(TileCli, EveryTreesTlobeKeepsTheBudget) {
    TempDir dir;
    const auto r = run_cli("--json " + run_tile(dir / "out", "--use-input-segmentation --budget-kb 2"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["options"]["budget_kb"].get<double>(), 2.0);
    std::size_t files = 0;
    for (const auto& entry : fs::directory_iterator(dir / "out" / "trees")) {
        if (entry.path().extension() != ".tlobe") continue;
        ++files;
        EXPECT_LE(fs::file_size(entry.path()), 2000u) << entry.path();
        EXPECT_NO_THROW(lobes::read_tlobe(entry.path()));
    }
    EXPECT_EQ(files, 5u);
}

TEST(TileCli, ResumeKeepsFinishedOutputsAndOverwriteRedoesThemIdentically) {
    TempDir dir;
    ASSERT_EQ(run_cli(run_tile(dir / "a")).exit_code, 0);
    const fs::path skeleton = dir / "a" / "trees" / "tree_0001_skeleton.ply";
    const auto made = fs::last_write_time(skeleton);
    const std::string csv = slurp(dir / "a" / "trees.csv");
    fs::copy_file(dir / "a" / "crowns.geojson", dir / "b_first_crowns.geojson");

    const auto again = run_cli("--json " + run_tile(dir / "a"));
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(nlohmann::json::parse(again.out)["counts"]["trees_reused"], 5);
    EXPECT_EQ(fs::last_write_time(skeleton), made);
    EXPECT_EQ(slurp(dir / "a" / "trees.csv"), csv);
    EXPECT_EQ(slurp(dir / "a" / "crowns.geojson"), slurp(dir / "b_first_crowns.geojson"));  // outlines kept in the records

    // A record made by another treelobes (another version or measures revision) is not kept.
    const fs::path record = dir / "a" / "trees" / "tree_0001.json";
    auto older = nlohmann::json::parse(slurp(record));
    older["options_key"] = "treelobes 0.0.9, records 1, " + older["options_key"].get<std::string>();
    std::ofstream(record) << older.dump();
    const auto upgraded = run_cli("--json " + run_tile(dir / "a"));
    ASSERT_EQ(upgraded.exit_code, 0) << upgraded.err;
    EXPECT_EQ(nlohmann::json::parse(upgraded.out)["counts"]["trees_reused"], 4);
    EXPECT_EQ(slurp(dir / "a" / "trees.csv"), csv);
    const auto remade = fs::last_write_time(skeleton);
    EXPECT_NE(remade, made);

    const auto redo = run_cli("--json " + run_tile(dir / "a", "--use-input-segmentation --overwrite"));
    ASSERT_EQ(redo.exit_code, 0) << redo.err;
    EXPECT_EQ(nlohmann::json::parse(redo.out)["counts"]["trees_reused"], 0);
    EXPECT_NE(fs::last_write_time(skeleton), remade);

    // A fresh run elsewhere gives the same bytes (deterministic, whatever the thread schedule).
    ASSERT_EQ(run_cli("--threads 1 " + run_tile(dir / "b")).exit_code, 0);
    for (const char* file : {"trees.csv", "trees.geojson", "crowns.geojson", "tile.forest", "dtm.asc", "top_view.png",
                             "trees/tree_0002.dbf6", "trees/tree_0002.tlobe", "trees/tree_0002_skeleton.ply", "trees/tree_0002.json"})
        EXPECT_EQ(slurp(dir / "a" / file), slurp(dir / "b" / file)) << file;
}

// The number of points of each labelled tree of the small tile.
std::map<int, std::size_t> tree_sizes(const PointCloud& cloud) {
    std::map<int, std::size_t> sizes;
    for (double id : cloud.extra("treeID")->values)
        if (id > 0) ++sizes[static_cast<int>(id)];
    return sizes;
}

std::vector<std::string> csv_cells(const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream in(line + ",");  // the trailing comma keeps an empty last cell
    for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
    return cells;
}

// The row of trees.csv (its lines) whose tree_id is `tree_id`, by column name; empty when none.
std::map<std::string, std::string> csv_row(const std::vector<std::string>& lines, int tree_id) {
    const std::vector<std::string> header = csv_cells(lines.at(0));
    for (std::size_t k = 1; k < lines.size(); ++k) {
        const std::vector<std::string> cells = csv_cells(lines[k]);
        if (cells.size() != header.size() || cells[1] != std::to_string(tree_id)) continue;
        std::map<std::string, std::string> row;
        for (std::size_t i = 0; i < header.size(); ++i) row[header[i]] = cells[i];
        return row;
    }
    return {};
}

TEST(TileCli, ATreeTooSmallForAModelIsMeasuredNotModelled) {
    TempDir dir;
    const auto sizes = tree_sizes(read_point_cloud(small_tile()));
    const auto smallest = std::min_element(sizes.begin(), sizes.end(), [](auto& a, auto& b) { return a.second < b.second; });
    const std::size_t limit = smallest->second + 1;
    const auto r = run_cli(run_tile(dir / "out", "--use-input-segmentation --min-tree-points " + std::to_string(limit)));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("1 measured only"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir / "out" / "failures.jsonl"));
    const auto lines = lines_of(slurp(dir / "out" / "trees.csv"));
    EXPECT_EQ(lines.size(), sizes.size() + 1);  // header + every tree
    auto row = csv_row(lines, smallest->first);
    EXPECT_EQ(row["model"], "too_few_points");
    EXPECT_EQ(row["points"], std::to_string(smallest->second));
    EXPECT_FALSE(row["height_m"].empty());
    EXPECT_TRUE(row["lobes"].empty() && row["woody_volume_m3"].empty());
    char name[32];
    std::snprintf(name, sizeof name, "tree_%04d.tlobe", smallest->first);
    EXPECT_FALSE(fs::exists(dir / "out" / "trees" / name));
    EXPECT_EQ(encode::ForestReader(dir / "out" / "tile.forest").size(), sizes.size() - 1);
    const auto summary = nlohmann::json::parse(slurp(dir / "out" / "summary.json"));
    EXPECT_EQ(summary["counts"]["trees"], sizes.size());
    EXPECT_EQ(summary["counts"]["trees_measured_only"], 1);
    EXPECT_EQ(summary["counts"]["trees_modelled"], sizes.size() - 1);
    for (const auto& [id, n] : sizes) {
        if (id == smallest->first) continue;
        EXPECT_EQ(csv_row(lines, id)["model"], "ok") << id;
    }
}

// The summary line names the stand preset the segmentation ran with (the choice decides most of
// the trees on a dense conifer stand, and nothing chooses it automatically); a tile that takes
// its input's segmentation ran none.
TEST(TileCli, TheSummaryLineNamesTheStandPreset) {
    TempDir dir;
    const std::string measure_only = " --min-tree-points 100000000";
    const auto broadleaf = run_cli(run_tile(dir / "broadleaf", measure_only));
    ASSERT_EQ(broadleaf.exit_code, 0) << broadleaf.err;
    EXPECT_NE(broadleaf.out.find("als segmentation (broadleaf stand): "), std::string::npos) << broadleaf.out;
    const auto conifer = run_cli(run_tile(dir / "conifer", "--stand conifer" + measure_only));
    ASSERT_EQ(conifer.exit_code, 0) << conifer.err;
    EXPECT_NE(conifer.out.find("als segmentation (conifer stand): "), std::string::npos) << conifer.out;
    const auto input = run_cli(run_tile(dir / "input", "--use-input-segmentation" + measure_only));
    ASSERT_EQ(input.exit_code, 0) << input.err;
    EXPECT_NE(input.out.find("input segmentation: "), std::string::npos) << input.out;
    EXPECT_EQ(input.out.find(" stand)"), std::string::npos) << input.out;
}

TEST(TileCli, ASparseAirborneSurveyIsSaidToBeSparse) {
    TempDir dir;
    const auto made =
            run_cli("--log-level warn synth tile --trees 6 --size 40 --seed 3 --scanner als --pulse-density 0.1 "
                    "--max-leaves 2000 --out " +
                    quoted(dir / "sparse"));
    ASSERT_EQ(made.exit_code, 0) << made.err;
    const std::string measure_only = " --mode als --min-tree-points 100000000";
    const std::string warning = "m apart), fewer than about 0.5: expect crowns split";
    const std::string too_sparse = "pulses per m^2 (first returns over its footprint), too few to tell single trees apart";
    const auto sparse = run_cli("tile " + quoted(dir / "sparse" / "tile.las") + " --out " + quoted(dir / "a") + measure_only);
    ASSERT_EQ(sparse.exit_code, 0) << sparse.err;
    EXPECT_NE(sparse.err.find("the survey holds about 0.1"), std::string::npos) << sparse.err;
    EXPECT_NE(sparse.err.find(warning), std::string::npos) << sparse.err;
    EXPECT_EQ(sparse.err.find(too_sparse), std::string::npos) << sparse.err;
    const auto chm = [&](const char* run) { return nlohmann::json::parse(slurp(dir / run / "summary.json"))["options"]["chm"]; };
    EXPECT_TRUE(chm("a")["sparse_survey"].get<bool>());
    EXPECT_NEAR(chm("a")["pulse_density_per_m2"].get<double>(), 0.1, 0.02);
    // A spacing given for the survey is taken as it is, and the dense sample tile is no sparse survey.
    const auto given =
            run_cli("tile " + quoted(dir / "sparse" / "tile.las") + " --out " + quoted(dir / "b") + measure_only + " --return-spacing 0.8");
    ASSERT_EQ(given.exit_code, 0) << given.err;
    EXPECT_EQ(given.err.find(warning), std::string::npos) << given.err;
    EXPECT_FALSE(chm("b")["sparse_survey"].get<bool>());
    const auto dense = run_cli(run_tile(dir / "c", measure_only));
    ASSERT_EQ(dense.exit_code, 0) << dense.err;
    EXPECT_EQ(dense.err.find(warning), std::string::npos) << dense.err;
    EXPECT_EQ(dense.err.find(too_sparse), std::string::npos) << dense.err;
    EXPECT_GT(chm("c")["pulse_density_per_m2"].get<double>(), 1.0);
    // A sparse survey's spacing given to a dense tile (batch passes the one it measured on a
    // typical tile): the warning names the spacing given, not this tile's density, as sparse.
    const auto given_sparse = run_cli(run_tile(dir / "e", measure_only + " --return-spacing 1.6"));
    ASSERT_EQ(given_sparse.exit_code, 0) << given_sparse.err;
    EXPECT_NE(given_sparse.err.find("the return spacing given, 1.60 m (--return-spacing, or the survey's from batch), is a sparse "
                                    "survey's, fewer than about 0.5 pulses per m^2 (this tile holds about "),
              std::string::npos)
            << given_sparse.err;
    EXPECT_EQ(given_sparse.err.find(warning), std::string::npos) << given_sparse.err;
    // A third of that tells too few crowns apart to be of use, and the warning says so.
    ASSERT_EQ(run_cli("--log-level warn synth tile --trees 6 --size 40 --seed 3 --scanner als --pulse-density 0.03 "
                      "--max-leaves 2000 --out " +
                      quoted(dir / "sparser"))
                      .exit_code,
              0);
    const auto sparser = run_cli("tile " + quoted(dir / "sparser" / "tile.las") + " --out " + quoted(dir / "d") + measure_only);
    ASSERT_EQ(sparser.exit_code, 0) << sparser.err;
    EXPECT_NE(sparser.err.find(too_sparse), std::string::npos) << sparser.err;
    EXPECT_EQ(sparser.err.find(warning), std::string::npos) << sparser.err;
    EXPECT_NEAR(chm("d")["pulse_density_per_m2"].get<double>(), 0.03, 0.01);
}

TEST(TileCli, ATreeThatFailsIsListedAndTheOthersGoOn) {
    TempDir dir;
    PointCloud cloud = read_point_cloud(small_tile());
    const auto sizes = tree_sizes(cloud);
    const int broken = sizes.rbegin()->first;  // its points all moved to one spot: no skeleton can be built
    const auto& ids = cloud.extra("treeID")->values;
    std::optional<Eigen::Vector3f> spot;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (static_cast<int>(ids[i]) == broken) {
            if (!spot) spot = cloud.positions[i];
            cloud.positions[i] = *spot;
        }
    write_point_cloud(cloud, dir / "broken.las");
    const auto r = run_cli("tile " + quoted(dir / "broken.las") + " --use-input-segmentation --out " + quoted(dir / "out"));
    EXPECT_EQ(r.exit_code, 3) << r.err;
    const auto failures = lines_of(slurp(dir / "out" / "failures.jsonl"));
    ASSERT_EQ(failures.size(), 1u);
    const auto failure = nlohmann::json::parse(failures[0]);
    EXPECT_EQ(failure["tree_id"], broken);
    EXPECT_EQ(failure["exit_code"], 2);
    EXPECT_NE(failure["reason"].get<std::string>().find("too few points"), std::string::npos) << failure.dump();
    EXPECT_EQ(lines_of(slurp(dir / "out" / "trees.csv")).size(), sizes.size());  // header + the others
    EXPECT_EQ(encode::ForestReader(dir / "out" / "tile.forest").size(), sizes.size() - 1);
}

TEST(TileCli, UsageErrors) {
    TempDir dir;
    EXPECT_EQ(run_cli("tile " + quoted(small_tile())).exit_code, 1);  // no --out
    EXPECT_EQ(run_cli(run_tile(dir / "o", "--mode xyz")).exit_code, 1);
    EXPECT_EQ(run_cli(run_tile(dir / "o", "--dtm-cell nan")).exit_code, 1);
    EXPECT_EQ(run_cli(run_tile(dir / "o", "--stand palm")).exit_code, 1);
    EXPECT_EQ(run_cli(run_tile(dir / "o", "--max-crown-radius 0")).exit_code, 1);
    const auto help = run_cli("tile --help");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.out.find("--use-input-segmentation"), std::string::npos);
    EXPECT_NE(help.out.find("--stand"), std::string::npos);
}

TEST(TileCli, InputSegmentationNeedsATreeIdAttribute) {
    TempDir dir;
    std::ofstream(dir / "plain.xyz") << "0 0 0\n1 0 0\n0 1 0\n1 1 5\n";
    const auto r = run_cli("tile " + quoted(dir / "plain.xyz") + " --out " + quoted(dir / "o") + " --use-input-segmentation");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("treeID"), std::string::npos);
}

// ---- bad tiles -------------------------------------------------------------------------

TEST(TileCliBadTiles, EmptyTileIsAClearError) {
    TempDir dir;
    std::ofstream(dir / "empty.xyz") << "";
    const auto r = run_cli("tile " + quoted(dir / "empty.xyz") + " --out " + quoted(dir / "o"));
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_FALSE(r.err.empty());
}

TEST(TileCliBadTiles, NanCoordinatesAreDroppedAndAllNanIsAnError) {
    TempDir dir;
    std::ofstream(dir / "nan.xyz") << "nan nan nan\nnan 1 2\n";
    const auto all = run_cli("tile " + quoted(dir / "nan.xyz") + " --out " + quoted(dir / "o"));
    EXPECT_EQ(all.exit_code, 2) << all.err;
    // The synthetic tile with a few NaN rows: they are dropped and counted, the rest goes on.
    PointCloud cloud = read_point_cloud(small_tile());
    std::string text;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p = cloud.global(i);
        text += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
        if (i % 5000 == 0) text += "nan 0 0\n";
    }
    std::ofstream(dir / "some_nan.xyz") << text;
    const auto r = run_cli("--json tile " + quoted(dir / "some_nan.xyz") + " --out " + quoted(dir / "p"));
    ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 3) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_GT(summary["counts"]["non_finite_dropped"].get<int>(), 0);
    EXPECT_TRUE(summary["crs"].is_null());  // a text file has no CRS
    EXPECT_FALSE(nlohmann::json::parse(slurp(dir / "p" / "trees.geojson")).contains("crs_wkt"));
}

TEST(TileCliBadTiles, AllGroundGivesTheDocumentedEmptyResult) {
    TempDir dir;
    std::string text;
    for (int x = 0; x < 60; ++x)
        for (int y = 0; y < 60; ++y)
            text += std::to_string(x * 0.5) + " " + std::to_string(y * 0.5) + " " + std::to_string(0.1 * x * 0.5) + "\n";
    std::ofstream(dir / "ground.xyz") << text;
    const auto r = run_cli("--json tile " + quoted(dir / "ground.xyz") + " --out " + quoted(dir / "o"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["counts"]["trees"], 0);
    EXPECT_NE(r.err.find("no trees found"), std::string::npos);
    EXPECT_EQ(lines_of(slurp(dir / "o" / "trees.csv")).size(), 1u);  // the header only
    EXPECT_TRUE(nlohmann::json::parse(slurp(dir / "o" / "trees.geojson"))["features"].empty());
    EXPECT_EQ(encode::ForestReader(dir / "o" / "tile.forest").size(), 0u);
    for (const char* file : {"dtm.asc", "points.las", "top_view.png", "summary.json"}) EXPECT_TRUE(fs::exists(dir / "o" / file)) << file;
}

// An unclassified tile's building: a box house (roof 6 m up, walls) on flat ground becomes a
// "tree" that trees.csv, the GeoJSON and one line on stderr mark as not looking like one.
TEST(TileCliBadTiles, AnUnclassifiedBuildingIsMarkedNotATree) {
    TempDir dir;
    std::string text;
    const auto point = [&](double x, double y, double z) {
        text += std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
    };
    for (int i = 0; i <= 60; ++i)
        for (int j = 0; j <= 60; ++j) point(0.5 * i, 0.5 * j, 0.0);
    for (int i = 0; i <= 32; ++i)
        for (int j = 0; j <= 32; ++j) point(10 + 0.25 * i, 10 + 0.25 * j, 6.0);
    for (int k = 0; k <= 32; ++k)
        for (int h = 1; h < 24; ++h) {
            point(10 + 0.25 * k, 10, 0.25 * h);
            point(10 + 0.25 * k, 18, 0.25 * h);
            point(10, 10 + 0.25 * k, 0.25 * h);
            point(18, 10 + 0.25 * k, 0.25 * h);
        }
    std::ofstream(dir / "house.xyz") << text;
    const auto r = run_cli("tile " + quoted(dir / "house.xyz") + " --mode als --out " + quoted(dir / "o"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("1 of 1 modelled trees do not look like trees"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("tree 1: does not look like a tree"), std::string::npos) << r.err;  // one line, not one per tree
    const auto lines = lines_of(slurp(dir / "o" / "trees.csv"));
    ASSERT_EQ(lines.size(), 2u);
    EXPECT_TRUE(lines[0].ends_with(",model,not_a_tree")) << lines[0];
    EXPECT_TRUE(lines[1].ends_with(",ok,true")) << lines[1];
    EXPECT_EQ(nlohmann::json::parse(slurp(dir / "o" / "trees.geojson"))["features"][0]["properties"]["not_a_tree"], true);
}

// A LAS 1.2 file gives its CRS as GeoTIFF keys: an EPSG code, here NAD83 / Oregon GIC Lambert
// (ft) without the unit keys. PROJ's registry tells its unit, and the run says so.
TEST(TileCliBadTiles, ACrsInFeetKnownOnlyByItsCodeIsSaid) {
    TempDir dir;
    PointCloud cloud = read_point_cloud(small_tile());
    const std::vector<std::uint16_t> keys = {1, 1, 0, 1, 3072, 0, 1, 2992};
    RawVlr directory{"LASF_Projection", 34735, "GeoKeyDirectoryTag", {}};
    for (std::uint16_t k : keys) {
        directory.data.push_back(static_cast<std::uint8_t>(k & 0xff));
        directory.data.push_back(static_cast<std::uint8_t>(k >> 8));
    }
    cloud.georef = {};
    cloud.georef.las_vlrs = {directory};
    write_point_cloud(cloud, dir / "feet.las");
    ASSERT_EQ(read_point_cloud(dir / "feet.las").georef.crs_wkt, "EPSG:2992");
    const auto r = run_cli("--json tile " + quoted(dir / "feet.las") + " --out " + quoted(dir / "o") + " --use-input-segmentation");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("the CRS measures lengths in foot (0.3048 m)"), std::string::npos) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["crs_unit"]["name"], "foot");
}

TEST(TileCliBadTiles, ASingleTree) {
    TempDir dir;
    ASSERT_EQ(
            run_cli("--log-level warn synth tile --trees 1 --size 12 --seed 5 --pulse-density 20 --max-leaves 2000 --species pine --out " +
                    quoted(dir / "synth"))
                    .exit_code,
            0);
    const auto r =
            run_cli("--json tile " + quoted(dir / "synth" / "tile.las") + " --out " + quoted(dir / "o") + " --use-input-segmentation");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["counts"]["trees"], 1);
    EXPECT_EQ(lines_of(slurp(dir / "o" / "trees.csv")).size(), 2u);
}

TEST(TileCliBuffer, OptionsAreCheckedAndMemoryIsRefusedBeforeReading) {
    TempDir dir;
    EXPECT_EQ(run_cli(run_tile(dir / "a", "--neighbours " + quoted(dir.path()))).exit_code, 1);  // --neighbours needs --buffer
    EXPECT_EQ(run_cli(run_tile(dir / "b", "--buffer 5 --tile-size 20")).exit_code, 1);           // tile.las is not a retile name
    EXPECT_EQ(run_cli(run_tile(dir / "c", "--buffer -1")).exit_code, 1);
    EXPECT_EQ(run_cli(run_tile(dir / "d", "--max-memory lots")).exit_code, 1);
    const auto refused = run_cli(run_tile(dir / "e", "--max-memory 100K"));
    EXPECT_EQ(refused.exit_code, 2);
    EXPECT_NE(refused.err.find("points need about"), std::string::npos) << refused.err;
    EXPECT_NE(refused.err.find("retile"), std::string::npos) << refused.err;
    EXPECT_FALSE(fs::exists(dir / "e"));
}

TEST(TileCliBuffer, WithoutNeighboursTheBufferChangesNothing) {
    // The tile alone in its folder: the buffer finds no points, the core (its header bounds) holds
    // every tree, and the outputs are those of a run without a buffer.
    TempDir dir;
    ASSERT_EQ(run_cli("--log-level warn " + run_tile(dir / "plain")).exit_code, 0);
    const auto r = run_cli("--log-level warn --json " + run_tile(dir / "buffered", "--use-input-segmentation --buffer 10"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["buffer"]["core"]["from"], "header bounds");
    EXPECT_EQ(summary["counts"]["buffer_points"], 0);
    EXPECT_EQ(summary["counts"]["trees_in_buffer"], 0);
    EXPECT_EQ(slurp(dir / "plain" / "trees.csv"), slurp(dir / "buffered" / "trees.csv"));
    EXPECT_EQ(slurp(dir / "plain" / "points.las"), slurp(dir / "buffered" / "points.las"));
}

// A buffer narrower than the airborne segmentation's reach (twice the crown radius and the CHM
// smoothing's 3 sigma) is said once
// on stderr and recorded in the summary; a wide enough one is not; the input's labels have no reach.
TEST(TileCliBuffer, ANarrowBufferIsSaidAndRecorded) {
    TempDir dir;
    const auto narrow = run_cli("--json " + run_tile(dir / "narrow", "--mode als --buffer 10"));
    ASSERT_TRUE(narrow.exit_code == 0 || narrow.exit_code == 3) << narrow.err;
    EXPECT_NE(narrow.err.find("--buffer 10"), std::string::npos) << narrow.err;
    EXPECT_NE(narrow.err.find("narrower than the airborne segmentation's reach (34.5"), std::string::npos) << narrow.err;
    const auto narrow_summary = nlohmann::json::parse(narrow.out);
    EXPECT_EQ(narrow_summary["buffer"]["segmentation_reach_m"], 34.5);
    EXPECT_EQ(narrow_summary["buffer"]["wide_enough"], false);

    const auto wide = run_cli("--json " + run_tile(dir / "wide", "--mode als --buffer 10 --max-crown-radius 2.5"));
    ASSERT_TRUE(wide.exit_code == 0 || wide.exit_code == 3) << wide.err;
    EXPECT_EQ(wide.err.find("narrower"), std::string::npos) << wide.err;
    EXPECT_EQ(nlohmann::json::parse(wide.out)["buffer"]["wide_enough"], true);

    const auto labels = run_cli("--json " + run_tile(dir / "labels", "--use-input-segmentation --buffer 10"));
    ASSERT_EQ(labels.exit_code, 0) << labels.err;
    EXPECT_TRUE(nlohmann::json::parse(labels.out)["buffer"]["segmentation_reach_m"].is_null());
}
