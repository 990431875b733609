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
    const bool has_letters =
        std::any_of(first_line.begin(), first_line.end(), [](unsigned char c) { return std::isalpha(c); });
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

TEST(InfoReal, EveryScanIsDescribedAndLazIsRejected) {
    const auto root = real_data_dir();
    ASSERT_FALSE(root.empty());
    int scans = 0;
    int described = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file() || is_licence_or_readme(entry.path()) || is_table(entry.path())) continue;
        const auto result = run_cli("info '" + entry.path().string() + "'");
        if (entry.path().extension() == ".laz") {
            EXPECT_EQ(result.exit_code, 2) << entry.path();
            EXPECT_NE(result.err.find("LAZ is not supported yet"), std::string::npos) << result.err;
            continue;
        }
        ++scans;
        EXPECT_EQ(result.exit_code, 0) << entry.path() << ": " << result.err;
        if (result.exit_code == 0) ++described;
    }
    EXPECT_GT(scans, 0);
    EXPECT_EQ(described, scans);  // every non-LAZ scan under ../shared/data, however many there are
}
