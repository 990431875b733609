// `treelobes info` on every real scan of ../shared/data (label `real`).
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

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

TEST(InfoReal, EveryScanIsDescribedAndLazIsRejected) {
    const auto root = real_data_dir();
    ASSERT_FALSE(root.empty());
    int described = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file()) continue;
        const auto ext = entry.path().extension().string();
        if (ext == ".md" || entry.path().filename() == "LICENSE") continue;
        const auto result = run_cli("info '" + entry.path().string() + "'");
        if (ext == ".laz") {
            EXPECT_EQ(result.exit_code, 2) << entry.path();
            EXPECT_NE(result.err.find("LAZ is not supported yet"), std::string::npos) << result.err;
        } else {
            EXPECT_EQ(result.exit_code, 0) << entry.path() << ": " << result.err;
            ++described;
        }
    }
    EXPECT_EQ(described, 19);  // every non-LAZ file listed in ../shared/data/README.md
}
