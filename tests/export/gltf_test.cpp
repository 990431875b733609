// glTF 2.0 binary of trees: structure (LOD nodes with MSFT_lod, materials, georeferenced node
// translations) and the Khronos glTF-Validator's verdict: no errors, no warnings.
#include "core/atomic_file.hpp"
#include "export/gltf.hpp"
#include "export/tree_geometry.hpp"
#include "sample_trees.hpp"
#include "support/test_support.hpp"
#include "validators.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>

using namespace treelobes;
using namespace treelobes::exporting;

namespace {

nlohmann::json json_chunk(const std::string& glb) {
    std::uint32_t length = 0;
    std::memcpy(&length, glb.data() + 12, 4);
    return nlohmann::json::parse(glb.substr(20, length));
}

GltfTree gltf_tree(const ExportTree& tree, int lods) {
    TreeGeometryOptions options;
    options.lods = lods;
    return {tree.name, tree.skeleton.origin, tree_lods(tree, options), {{"height", 3.0}}, tree.species};
}

ExportTree tree_with_lobes(const Eigen::Vector3d& origin) {
    ExportTree tree{"oak", test::sample_tree(origin), {}, "Quercus robur", {}};
    for (const Eigen::Vector3f& centre : {Eigen::Vector3f(1.2f, 0.2f, 2.6f), Eigen::Vector3f(-0.6f, 0.3f, 2.9f)}) {
        TriangleMesh lobe = test::octahedron(centre, 0.4f);
        lobe.origin = origin;
        tree.lobes.push_back(lobe);
    }
    return tree;
}

void expect_valid(const std::filesystem::path& file) {
    const test::ValidatorRun run = test::validate_gltf(file);
    ASSERT_TRUE(run.available);
    EXPECT_EQ(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("errors 0, warnings 0"), std::string::npos) << run.output;
}

}  // namespace

TEST(Gltf, OneTreeWithThreeLodsIsValid) {
    test::TempDir dir;
    const ExportTree tree{"t1", test::sample_tree(), {}, "", {}};
    const std::string glb = glb_bytes({gltf_tree(tree, 3)}, tree.skeleton.origin);
    EXPECT_EQ(glb, glb_bytes({gltf_tree(tree, 3)}, tree.skeleton.origin));  // deterministic
    write_file_atomically(dir / "t1.glb", glb);
    expect_valid(dir / "t1.glb");

    const auto doc = json_chunk(glb);
    EXPECT_EQ(doc["asset"]["version"], "2.0");
    ASSERT_EQ(doc["scenes"][0]["nodes"].size(), 1u);
    ASSERT_EQ(doc["nodes"].size(), 3u);
    const auto& main = doc["nodes"][0];
    EXPECT_EQ(main["extensions"]["MSFT_lod"]["ids"], nlohmann::json({1, 2}));
    EXPECT_EQ(main["extras"]["MSFT_screencoverage"].size(), 3u);
    EXPECT_EQ(doc["extensionsUsed"], nlohmann::json({"MSFT_lod"}));
    EXPECT_FALSE(doc.contains("extensionsRequired"));
    EXPECT_FALSE(main.contains("translation"));  // the scene origin is the tree's origin
    // Bark and foliage primitives with their materials; fewer triangles at coarser LODs.
    const auto& lod0 = doc["meshes"][main["mesh"].get<int>()]["primitives"];
    ASSERT_EQ(lod0.size(), 2u);
    EXPECT_EQ(doc["materials"][lod0[0]["material"].get<int>()]["name"], "bark");
    EXPECT_EQ(doc["materials"][lod0[1]["material"].get<int>()]["name"], "foliage");
    const auto triangles = [&](int node) {
        const auto& p = doc["meshes"][doc["nodes"][node]["mesh"].get<int>()]["primitives"][0];
        return doc["accessors"][p["indices"].get<int>()]["count"].get<int>() / 3;
    };
    EXPECT_GT(triangles(0), triangles(1));
    EXPECT_GT(triangles(1), triangles(2));
    // y-up: the 3 m trunk spans y, the tree's up axis.
    const auto& position = doc["accessors"][lod0[0]["attributes"]["POSITION"].get<int>()];
    EXPECT_GT(position["max"][1].get<double>(), 2.9);
    EXPECT_LT(position["max"][2].get<double>() - position["min"][2].get<double>(), 1.5);
}

TEST(Gltf, TwoTreesWithLobesAreValidAndPlacedRelativeToTheSceneOrigin) {
    test::TempDir dir;
    const Eigen::Vector3d a(500000, 5400000, 300), b(500010, 5400004, 301);
    const std::string glb = glb_bytes({gltf_tree(tree_with_lobes(a), 2), gltf_tree({"t2", test::sample_tree(b), {}, "", {}}, 2)}, a);
    write_file_atomically(dir / "two.glb", glb);
    expect_valid(dir / "two.glb");
    const auto doc = json_chunk(glb);
    ASSERT_EQ(doc["scenes"][0]["nodes"].size(), 2u);
    const auto& second = doc["nodes"][doc["scenes"][0]["nodes"][1].get<int>()];
    EXPECT_EQ(second["translation"], nlohmann::json({10.0, 1.0, -4.0}));  // (dx, dz, -dy)
    EXPECT_EQ(doc["nodes"][0]["extras"]["species"], "Quercus robur");
    // The lobe tree's foliage: both octahedra (8 triangles each) at every LOD.
    const auto& foliage = doc["meshes"][doc["nodes"][0]["mesh"].get<int>()]["primitives"][1];
    EXPECT_EQ(doc["accessors"][foliage["indices"].get<int>()]["count"], 2 * 8 * 3);
}

TEST(Gltf, TheValidatorRejectsABrokenFile) {
    test::TempDir dir;
    const ExportTree tree{"t1", test::sample_tree(), {}, "", {}};
    std::string glb = glb_bytes({gltf_tree(tree, 1)}, tree.skeleton.origin);
    const std::size_t mode = glb.find("\"mode\":4");
    ASSERT_NE(mode, std::string::npos);
    glb[mode + 7] = '9';  // not a primitive mode: the validator must say so
    write_file_atomically(dir / "broken.glb", glb);
    const test::ValidatorRun run = test::validate_gltf(dir / "broken.glb");
    ASSERT_TRUE(run.available);
    EXPECT_EQ(run.exit_code, 1) << run.output;
}

TEST(Gltf, LodOptionsOutOfRangeAreUsageErrors) {
    const ExportTree tree{"t1", test::sample_tree(), {}, "", {}};
    TreeGeometryOptions options;
    options.lods = 0;
    EXPECT_EQ(test::error_code_of([&] { tree_lods(tree, options); }), ExitCode::Usage);
    options.lods = 2;
    options.sides = 2;
    EXPECT_EQ(test::error_code_of([&] { tree_lods(tree, options); }), ExitCode::Usage);
}
