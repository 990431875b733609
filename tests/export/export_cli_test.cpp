// `treelobes export` end to end: every format from a skeleton PLY, .tlobe, .dbf6, .forest and a
// folder; `info` reads what export writes; bad inputs give one line and exit 2 / 1.
#include "core/atomic_file.hpp"
#include "core/georef_sidecar.hpp"
#include "core/skeleton_io.hpp"
#include "encode/forest_file.hpp"
#include "encode/tree_file.hpp"
#include "export/cityjson.hpp"
#include "export/tree_input.hpp"
#include "lobes/tlobe_io.hpp"
#include "sample_trees.hpp"
#include "support/test_support.hpp"
#include "validators.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <filesystem>

using namespace treelobes;
using test::quoted;
using test::run_cli;

namespace {

const Eigen::Vector3d kOrigin(500000.0, 5400000.0, 300.0);

nlohmann::json info_of(const std::filesystem::path& file) {
    const auto result = run_cli("info --json " + quoted(file));
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return result.exit_code == 0 ? nlohmann::json::parse(result.out)["files"][0] : nlohmann::json();
}

test::CommandResult export_to(const std::filesystem::path& input, const std::string& format, const std::filesystem::path& out,
                              const std::string& extra = "") {
    return run_cli("export " + quoted(input) + " --format " + format + " --out " + quoted(out) + " " + extra);
}

int lines(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

void expect_bounds_near(const nlohmann::json& info, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double tolerance) {
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(info["bounds"]["min"][k].get<double>(), lo[k], tolerance) << info.dump();
        EXPECT_NEAR(info["bounds"]["max"][k].get<double>(), hi[k], tolerance) << info.dump();
    }
}

lobes::LobeTree lobe_tree() {
    lobes::LobeTree t;
    t.skeleton = test::sample_tree(kOrigin);
    t.species = "Quercus robur";
    t.root_diameter = 0.24;
    lobes::Lobe lobe;
    lobe.mesh = test::octahedron({1.2f, 0.2f, 2.6f}, 0.4f);
    lobe.seed_node = 6;
    lobe.points = 500;
    t.lobes.push_back(lobe);
    return t;
}

}  // namespace

TEST(ExportCli, SkeletonToEveryFormatAndInfoReadsThemBack) {
    test::TempDir dir;
    write_skeleton_ply(test::sample_tree(kOrigin), dir / "tree.ply");
    // Node bounds of the sample tree: x -0.8 .. 1.4, y 0 .. 0.5, z 0 .. 3 (plus radii / leaves).
    const Eigen::Vector3d lo = kOrigin + Eigen::Vector3d(-0.8, 0, 0), hi = kOrigin + Eigen::Vector3d(1.4, 0.5, 3.0);

    auto r = export_to(dir / "tree.ply", "qsm-txt", dir / "tree_qsm.txt", "--json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    EXPECT_EQ(summary["outputs"].size(), 3u);  // cylinders, branch and tree tables
    EXPECT_NEAR(summary["trees"][0]["height"].get<double>(), 3.0, 1e-4);
    EXPECT_TRUE(std::filesystem::exists(dir / "tree_qsm_branch.txt"));
    EXPECT_TRUE(std::filesystem::exists(dir / "tree_qsm_tree.txt"));
    auto info = info_of(dir / "tree_qsm.txt");
    EXPECT_EQ(info["kind"], "qsm");
    EXPECT_EQ(info["cylinders"], 10);
    expect_bounds_near(info, lo, hi, 1e-3);

    ASSERT_EQ(export_to(dir / "tree.ply", "qsm-csv", dir / "tree_qsm.csv").exit_code, 0);
    info = info_of(dir / "tree_qsm.csv");
    EXPECT_EQ(info["format"], "csv");
    EXPECT_EQ(info["cylinders"], 10);

    r = export_to(dir / "tree.ply", "glb", dir / "tree.glb", "--crs EPSG:25832");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto sidecar = read_georef_sidecar(dir / "tree.glb");
    ASSERT_TRUE(sidecar);
    EXPECT_EQ(sidecar->origin, kOrigin);
    EXPECT_EQ(sidecar->crs_wkt, "EPSG:25832");
    info = info_of(dir / "tree.glb");
    EXPECT_EQ(info["format"], "glb");
    EXPECT_EQ(info["nodes"], 1);
    EXPECT_GT(info["faces"].get<int>(), 100);
    expect_bounds_near(info, lo, hi, 0.2);  // tubes and leaf cards reach beyond the nodes
    const test::ValidatorRun valid = test::validate_gltf(dir / "tree.glb");
    EXPECT_EQ(valid.exit_code, 0) << valid.output;

    ASSERT_EQ(export_to(dir / "tree.ply", "cityjson", dir / "tree.city.json", "--crs EPSG:25832").exit_code, 0);
    info = info_of(dir / "tree.city.json");
    EXPECT_EQ(info["kind"], "city model");
    EXPECT_EQ(info["city_objects"], 1);
    EXPECT_EQ(info["crs"], "https://www.opengis.net/def/crs/EPSG/0/25832");
    expect_bounds_near(info, lo, hi, 0.15);

    for (const char* format : {"ply", "obj"}) {
        const auto out = dir / (std::string("tree_mesh.") + format);
        ASSERT_EQ(export_to(dir / "tree.ply", format, out, "--crs EPSG:25832").exit_code, 0) << format;
        info = info_of(out);
        EXPECT_EQ(info["kind"], "mesh");
        expect_bounds_near(info, lo, hi, 0.15);
        ASSERT_TRUE(read_georef_sidecar(out)) << format;
        EXPECT_EQ(read_georef_sidecar(out)->crs_wkt, "EPSG:25832");
    }
}

TEST(ExportCli, TlobeDbf6ForestAndFolderInputs) {
    test::TempDir dir;
    lobes::write_tlobe(lobe_tree(), dir / "oak.tlobe");
    auto r = export_to(dir / "oak.tlobe", "cityjson", dir / "oak.city.json", "--json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["trees"][0]["lobes"], 1);
    const auto city = nlohmann::json::parse(read_file(dir / "oak.city.json"));
    EXPECT_EQ(city["CityObjects"]["oak"]["attributes"]["species"], "Quercus robur");
    ASSERT_EQ(export_to(dir / "oak.tlobe", "glb", dir / "oak.glb").exit_code, 0);
    const test::ValidatorRun valid = test::validate_gltf(dir / "oak.glb");
    EXPECT_EQ(valid.exit_code, 0) << valid.output;

    encode::TreeFileOptions options;
    options.lods = 2;
    encode::write_tree_file(encode::store_tree(test::sample_tree(kOrigin), options), dir / "tree.dbf6");
    ASSERT_EQ(export_to(dir / "tree.dbf6", "qsm-csv", dir / "dbf6.csv").exit_code, 0);
    EXPECT_GT(info_of(dir / "dbf6.csv")["cylinders"].get<int>(), 5);
    EXPECT_EQ(export_to(dir / "tree.dbf6", "qsm-csv", dir / "lod9.csv", "--lod 9").exit_code, 1);  // a LOD not stored

    std::vector<encode::ForestTree> forest{{test::sample_tree({0, 0, 0}), kOrigin, 0.0f, "a"},
                                           {test::sample_tree({0, 0, 0}), kOrigin + Eigen::Vector3d(8, 3, 0), 1.0f, "b"}};
    encode::write_forest_file(forest, {}, dir / "stand.forest");
    r = export_to(dir / "stand.forest", "qsm-txt", dir / "stand_qsm", "--json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "stand_qsm" / "a.txt"));
    EXPECT_TRUE(std::filesystem::exists(dir / "stand_qsm" / "b_tree.txt"));
    ASSERT_EQ(export_to(dir / "stand.forest", "glb", dir / "stand.glb").exit_code, 0);
    EXPECT_EQ(info_of(dir / "stand.glb")["nodes"], 2);

    // A folder (a tile's output): skeletons, a .tlobe and files that are not trees.
    const auto folder = dir / "tile";
    std::filesystem::create_directories(folder / "trees");
    write_skeleton_ply(test::sample_tree(kOrigin), folder / "trees" / "t1.ply");
    write_skeleton_ply(test::sample_tree(kOrigin + Eigen::Vector3d(5, 0, 0)), folder / "trees" / "t2.ply");
    lobes::write_tlobe(lobe_tree(), folder / "t3.tlobe");
    test::write_text(folder / "summary.json", "{}\n");
    ASSERT_EQ(export_to(folder, "cityjson", dir / "tile.city.json").exit_code, 0);
    EXPECT_EQ(info_of(dir / "tile.city.json")["city_objects"], 3);
    // --instances: one template per species (the two skeletons have none, the .tlobe is an oak).
    ASSERT_EQ(export_to(folder, "cityjson", dir / "instances.city.json", "--instances").exit_code, 0);
    const test::ValidatorRun instances = test::validate_cityjson(dir / "instances.city.json");
    EXPECT_EQ(instances.exit_code, 0) << instances.output;
    const auto with_instances = nlohmann::json::parse(read_file(dir / "instances.city.json"));
    EXPECT_EQ(with_instances["geometry-templates"]["templates"].size(), 2u);
    EXPECT_TRUE(exporting::check_cityjson(read_file(dir / "instances.city.json")).empty());
    EXPECT_EQ(export_to(folder, "glb", dir / "x.glb", "--instances").exit_code, 1);  // CityJSON only
}

TEST(ExportCli, BadInputsGiveOneLineAndExitCodes) {
    test::TempDir dir;
    lobes::write_tlobe(lobe_tree(), dir / "oak.tlobe");
    const std::string bytes = read_file(dir / "oak.tlobe");
    write_file_atomically(dir / "cut.tlobe", bytes.substr(0, bytes.size() / 2));
    auto r = export_to(dir / "cut.tlobe", "glb", dir / "cut.glb");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(lines(r.err), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "cut.glb"));

    // Four vertices, three edges, but 0-1-2 is a cycle and vertex 3 hangs loose.
    test::write_text(dir / "cycle.ply",
                     "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                     "property float radius\nelement edge 3\nproperty int vertex1\nproperty int vertex2\nend_header\n"
                     "0 0 0 0.1\n0 0 1 0.1\n0 1 1 0.1\n0 2 2 0.1\n0 1\n1 2\n2 0\n");
    r = export_to(dir / "cycle.ply", "qsm-txt", dir / "cycle.txt");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(lines(r.err), 1) << r.err;

    write_skeleton_ply(test::sample_tree(kOrigin), dir / "tree.ply");
    r = export_to(dir / "tree.ply", "shp", dir / "tree.shp");
    EXPECT_EQ(r.exit_code, 1);
    r = export_to(dir / "missing.ply", "glb", dir / "x.glb");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(lines(r.err), 1) << r.err;
    r = export_to(dir / "tree.ply", "glb", dir / "x.glb", "--lods 0");
    EXPECT_EQ(r.exit_code, 1);
}

TEST(ExportCli, ConfidenceFromTheRecordBesideTheTlobe) {
    test::TempDir dir;
    // A tile's record (tree_NNNN.json, "points": all the tree's points) beside its .tlobe whose
    // one lobe holds 500 points: 1 - 500 / 2000.
    lobes::write_tlobe(lobe_tree(), dir / "tree_0001.tlobe");
    test::write_text(dir / "tree_0001.json", R"({"tree_id": 1, "points": 2000})");
    EXPECT_NEAR(exporting::tree_confidence(dir / "tree_0001.tlobe", 500).value(), 0.75, 1e-12);
    auto r = export_to(dir / "tree_0001.tlobe", "cityjson", dir / "t.city.json", "--json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NEAR(nlohmann::json::parse(r.out)["trees"][0]["confidence"].get<double>(), 0.75, 1e-9);
    const auto city = nlohmann::json::parse(read_file(dir / "t.city.json"));
    EXPECT_EQ(city["CityObjects"]["tree_0001"]["attributes"]["confidence"], 0.75);
    const test::ValidatorRun valid_city = test::validate_cityjson(dir / "t.city.json");
    EXPECT_EQ(valid_city.exit_code, 0) << valid_city.output;
    // glb: in the tree node's extras.
    ASSERT_EQ(export_to(dir / "tree_0001.tlobe", "glb", dir / "t.glb").exit_code, 0);
    const std::string glb = read_file(dir / "t.glb");
    std::uint32_t json_length = 0;
    std::memcpy(&json_length, glb.data() + 12, 4);
    const auto gltf = nlohmann::json::parse(glb.substr(20, json_length));
    EXPECT_NEAR(gltf["nodes"][0]["extras"]["confidence"].get<double>(), 0.75, 1e-6);
    const test::ValidatorRun valid_glb = test::validate_gltf(dir / "t.glb");
    EXPECT_EQ(valid_glb.exit_code, 0) << valid_glb.output;

    // `treelobes lobes` writes <stem>_lobes.json with the main and lobe points: the same ratio.
    r = run_cli("lobes " + quoted(test::source_dir() / "data/synthetic/lagerstroemia_2.las") + " --out " + quoted(dir / "lobes"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto points = nlohmann::json::parse(read_file(dir / "lobes" / "lagerstroemia_2_lobes.json"))["points"];
    const double expected = points["main"].get<double>() / (points["main"].get<double>() + points["lobes"].get<double>());
    r = export_to(dir / "lobes" / "lagerstroemia_2.tlobe", "cityjson", dir / "l.city.json", "--json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NEAR(nlohmann::json::parse(r.out)["trees"][0]["confidence"].get<double>(), expected, 1e-9);

    // No record: no confidence; a record that is not JSON: exit 2.
    lobes::write_tlobe(lobe_tree(), dir / "alone.tlobe");
    ASSERT_EQ(export_to(dir / "alone.tlobe", "cityjson", dir / "a.city.json").exit_code, 0);
    EXPECT_FALSE(nlohmann::json::parse(read_file(dir / "a.city.json"))["CityObjects"]["alone"]["attributes"].contains("confidence"));
    test::write_text(dir / "alone.json", "{points");
    r = export_to(dir / "alone.tlobe", "cityjson", dir / "a.city.json");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(lines(r.err), 1) << r.err;
}
