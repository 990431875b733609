// `treelobes info` on every real scan of ../shared/data (label `real`).
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <string>

using treelobes::test::real_data;
using treelobes::test::real_data_dir;
using treelobes::test::run_cli;

TEST(InfoReal, MixedConiferReportsCountFormatAndTreeId) {
    const auto file = real_data("lidr/MixedConifer.las");
    const auto result = run_cli("info --json '" + file.string() + "'");
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const auto info = nlohmann::json::parse(result.out)["files"][0];
    EXPECT_EQ(info["points"], 37657);
    EXPECT_EQ(info["version"], "1.2");
    EXPECT_EQ(info["point_format"], 1);
    bool has_tree_id = false;
    for (const auto& attribute : info["attributes"]) has_tree_id |= attribute["name"] == "treeID";
    EXPECT_TRUE(has_tree_id) << info.dump();
}

namespace {

bool is_licence_or_readme(const std::filesystem::path& path) {
    const auto name = path.filename().string();
    return path.extension() == ".md" || name.rfind("LICENSE", 0) == 0 || name.rfind("README", 0) == 0;
}

// A table (e.g. idtrees/labels.csv) has a header whose first column is not a coordinate:
// it describes scans, it is not one.
bool is_table(const std::filesystem::path& path) {
    if (path.extension() != ".csv" && path.extension() != ".txt") return false;
    std::ifstream in(path);
    std::string first_line;
    std::getline(in, first_line);
    const bool has_letters = std::any_of(first_line.begin(), first_line.end(), [](unsigned char c) { return std::isalpha(c); });
    return has_letters && !(first_line.rfind("x", 0) == 0 || first_line.rfind("X", 0) == 0);
}

}  // namespace

TEST(InfoReal, TablesAndLicencesAreNotScans) {
    const auto root = real_data_dir();
    ASSERT_FALSE(root.empty());
    EXPECT_TRUE(is_table(root / "idtrees" / "labels.csv"));
    EXPECT_FALSE(is_table(root / "woodske" / "HS_wood.csv"));
    EXPECT_FALSE(is_table(root / "archi" / "tree1_treeqsm_cylinders.txt"));
    EXPECT_TRUE(is_licence_or_readme(root / "woodske" / "LICENSE"));
}

TEST(InfoReal, EveryScanIncludingLazIsDescribed) {
    const auto root = real_data_dir();
    ASSERT_FALSE(root.empty());
    int scans = 0;
    int described = 0;
    int laz = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file() || is_licence_or_readme(entry.path()) || is_table(entry.path())) continue;
        const auto result = run_cli("info '" + entry.path().string() + "'");
        ++scans;
        EXPECT_EQ(result.exit_code, 0) << entry.path() << ": " << result.err;
        if (result.exit_code == 0) ++described;
        if (entry.path().extension() == ".laz") {
            ++laz;
            EXPECT_NE(result.out.find("LAZ (point format "), std::string::npos) << result.out;
        }
    }
    EXPECT_GT(scans, 0);
    EXPECT_GT(laz, 0);
    EXPECT_EQ(described, scans);  // every scan under ../shared/data, LAZ included, however many there are
}

TEST(InfoReal, LazAndCopcAreDescribedInJson) {
    const auto laz = run_cli("info --json '" + real_data("laz/MixedConifer.laz").string() + "'");
    ASSERT_EQ(laz.exit_code, 0) << laz.err;
    const auto info = nlohmann::json::parse(laz.out)["files"][0];
    EXPECT_EQ(info["format"], "laz");
    EXPECT_EQ(info["points"], 37657);
    EXPECT_EQ(info["laz"]["point_format"], 1);
    EXPECT_EQ(info["laz"]["chunk_size"], 50000);
    bool has_tree_id = false;
    for (const auto& attribute : info["attributes"]) has_tree_id |= attribute["name"] == "treeID";
    EXPECT_TRUE(has_tree_id) << info.dump();

    const auto copc_file = real_data("laz/laspy/simple.copc.laz").string();
    const auto copc = run_cli("info --json '" + copc_file + "'");
    ASSERT_EQ(copc.exit_code, 0) << copc.err;
    const auto c = nlohmann::json::parse(copc.out)["files"][0];
    EXPECT_EQ(c["laz"]["chunk_size"], "variable");
    EXPECT_GE(c["copc"]["levels"].get<int>(), 1);
    EXPECT_GT(c["copc"]["nodes"].get<int>(), 1);

    // A bounds query reads fewer nodes and counts only the points inside.
    const auto& lo = c["bounds"]["min"];
    const auto& hi = c["bounds"]["max"];
    const double mid_x = (lo[0].get<double>() + hi[0].get<double>()) / 2, mid_y = (lo[1].get<double>() + hi[1].get<double>()) / 2;
    const std::string box = std::to_string(lo[0].get<double>() - 1) + "," + std::to_string(lo[1].get<double>() - 1) + "," +
                            std::to_string(mid_x) + "," + std::to_string(mid_y);
    const auto part = run_cli("info --json --bounds " + box + " '" + copc_file + "'");
    ASSERT_EQ(part.exit_code, 0) << part.err;
    const auto p = nlohmann::json::parse(part.out)["files"][0];
    EXPECT_LT(p["points"].get<int>(), c["points"].get<int>());
    EXPECT_GT(p["points"].get<int>(), 0);
    EXPECT_LT(p["copc"]["nodes_read"].get<int>(), p["copc"]["nodes"].get<int>());
    EXPECT_EQ(p["bounds_query"], true);
    EXPECT_LE(p["bounds"]["max"][0].get<double>(), mid_x);
}
