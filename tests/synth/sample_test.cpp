// The committed sample in data/synthetic/ (scripts/regenerate_synthetic.sh): every file is
// readable and its labels agree with its truth files, so the demo and other stages' tests can
// rely on it.
#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/skeleton_io.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <set>
#include <sstream>

using namespace treelobes;

namespace {

std::filesystem::path sample() { return test::source_dir() / "data" / "synthetic"; }

}  // namespace

TEST(SynthSample, SingleTreeLabelsMatchTheirTruth) {
    int trees = 0;
    for (const auto& entry : std::filesystem::directory_iterator(sample())) {
        if (entry.path().extension() != ".las") continue;
        SCOPED_TRACE(entry.path().filename().string());
        const std::string stem = entry.path().stem().string();
        const auto truth = nlohmann::json::parse(read_file(sample() / (stem + "_truth.json")));
        const PointCloud cloud = read_las(entry.path());
        const TreeGraph skeleton = read_skeleton_ply(sample() / (stem + "_skeleton.ply"));
        EXPECT_EQ(cloud.size(), truth["scan"]["points"].get<std::size_t>());
        EXPECT_EQ(skeleton.size(), truth["tree"]["internodes"].get<std::size_t>() + 1);
        const auto* tree = cloud.extra("treeID");
        const auto* species = cloud.extra("species");
        const auto* internode = cloud.extra("internode");
        ASSERT_TRUE(tree && species && internode);
        std::size_t on_tree = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            if (tree->values[i] == 0) continue;
            ++on_tree;
            ASSERT_EQ(species->values[i], truth["species_id"].get<int>());
            ASSERT_GE(internode->values[i], 1);
            ASSERT_LT(internode->values[i], static_cast<double>(skeleton.size()));
        }
        EXPECT_GT(on_tree, 1000u);  // the rest is ground
        ++trees;
    }
    EXPECT_GE(trees, 3);
}

TEST(SynthSample, TileTruthAndLabelsAgree) {
    std::istringstream csv(read_file(sample() / "tile" / "truth.csv"));
    std::string line;
    std::getline(csv, line);
    std::set<int> ids;
    while (std::getline(csv, line)) {
        const int id = std::stoi(line.substr(0, line.find(',')));
        ids.insert(id);
    }
    ASSERT_GE(ids.size(), 24u);  // dozens of trees: the demo's tile
    const PointCloud cloud = read_las(sample() / "tile" / "tile.las");
    std::set<int> seen;
    for (double v : cloud.extra("treeID")->values) seen.insert(static_cast<int>(v));
    seen.erase(0);
    EXPECT_EQ(seen, ids);  // every tree is hit, and no label without a truth row
}
