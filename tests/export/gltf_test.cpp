// glTF 2.0 binary of trees: structure (LOD nodes with MSFT_lod, materials, georeferenced node
// translations), the Khronos glTF-Validator's verdict (no errors, no warnings) and the triangles
// core/glb_mesh_io.cpp reads back.
#include "core/atomic_file.hpp"
#include "core/georef_sidecar.hpp"
#include "core/mesh_io.hpp"
#include "export/gltf.hpp"
#include "export/tree_geometry.hpp"
#include "render/image.hpp"
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

// The bytes of buffer view `view` (BIN chunk after the JSON chunk).
std::string view_bytes(const std::string& glb, const nlohmann::json& doc, int view) {
    std::uint32_t json_length = 0;
    std::memcpy(&json_length, glb.data() + 12, 4);
    const std::size_t bin = 20 + json_length + 8;
    const auto& v = doc["bufferViews"][view];
    return glb.substr(bin + v.value("byteOffset", 0), v["byteLength"].get<std::size_t>());
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
    EXPECT_EQ(doc["materials"][lod0[1]["material"].get<int>()]["name"], "leaves");  // leaf cards of a bare skeleton
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

// core/glb_mesh_io.cpp reads our export back: the same triangles, in the same order, at the
// same world coordinates (the scene origin comes from the georef sidecar), named by material.
TEST(Gltf, ReadBackGivesTheExportedTriangles) {
    test::TempDir dir;
    const Eigen::Vector3d a(500000, 5400000, 300), b(500010.5, 5400004.25, 301);
    const std::vector<GltfTree> trees{gltf_tree(tree_with_lobes(a), 1), gltf_tree({"t2", test::sample_tree(b), {}, "", {}}, 1)};
    write_file_atomically(dir / "two.glb", glb_bytes(trees, a));
    write_georef_sidecar(dir / "two.glb", a, {});
    const NamedMesh back = read_named_mesh(dir / "two.glb");
    EXPECT_EQ(back.report.format, "glb");
    EXPECT_EQ(back.report.degenerate_faces, 0u);

    std::size_t face = 0;
    for (const GltfTree& tree : trees)
        for (const TriangleMesh* part : {&tree.lods[0].wood, &tree.lods[0].foliage})
            for (const auto& f : part->faces) {
                ASSERT_LT(face, back.mesh.faces.size());
                for (int k = 0; k < 3; ++k) {
                    const Eigen::Vector3d expected = tree.origin + part->vertices[static_cast<std::size_t>(f[k])].cast<double>();
                    const Eigen::Vector3d got =
                            back.mesh.origin + back.mesh.vertices[static_cast<std::size_t>(back.mesh.faces[face][k])].cast<double>();
                    ASSERT_LT((got - expected).norm(), 1e-4)
                            << "face " << face << ": " << got.transpose() << " vs " << expected.transpose();
                }
                const FaceNames& names = back.names[back.face_names[face]];
                EXPECT_EQ(names.material, part == &tree.lods[0].wood ? "bark" : tree.name == "oak" ? "foliage" : "leaves");
                EXPECT_EQ(names.group, tree.name);
                EXPECT_EQ(names.object, tree.name);
                ++face;
            }
    EXPECT_EQ(face, back.mesh.faces.size());
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

TEST(Gltf, LeafCardsAreTexturedQuadsWithAnAlphaMask) {
    test::TempDir dir;
    const ExportTree tree{"t1", test::sample_tree(), {}, "", {}};
    const std::string glb = glb_bytes({gltf_tree(tree, 2)}, tree.skeleton.origin);
    write_file_atomically(dir / "leaves.glb", glb);
    expect_valid(dir / "leaves.glb");  // the validator also decodes the embedded PNG
    const auto doc = json_chunk(glb);

    // One PNG in the BIN chunk, a texture with a sampler, and the alpha-masked leaf material.
    ASSERT_EQ(doc["images"].size(), 1u);
    EXPECT_EQ(doc["images"][0]["mimeType"], "image/png");
    EXPECT_EQ(doc["textures"][0]["source"], 0);
    EXPECT_EQ(doc["textures"][0]["sampler"], 0);
    const auto& leaves = doc["materials"][2];
    EXPECT_EQ(leaves["name"], "leaves");
    EXPECT_EQ(leaves["alphaMode"], "MASK");
    EXPECT_EQ(leaves["alphaCutoff"], 0.5);
    EXPECT_EQ(leaves["doubleSided"], true);
    EXPECT_EQ(leaves["pbrMetallicRoughness"]["baseColorTexture"]["index"], 0);
    const render::Image leaf = render::decode_png(view_bytes(glb, doc, doc["images"][0]["bufferView"].get<int>()), "leaf");
    EXPECT_EQ(leaf.width, 64);
    EXPECT_EQ(leaf.height, 64);
    std::size_t opaque = 0, green = 0;
    for (int y = 0; y < leaf.height; ++y)
        for (int x = 0; x < leaf.width; ++x) {
            const render::Rgba c = leaf.at(x, y);
            ASSERT_TRUE(c[3] == 0 || c[3] == 255) << "partial alpha at " << x << "," << y;
            opaque += c[3] == 255;
            green += c[3] == 255 && c[1] > c[0] && c[1] > c[2];
        }
    EXPECT_GT(opaque, 64u * 64 * 3 / 10);  // a leaf, not a dot...
    EXPECT_LT(opaque, 64u * 64 * 8 / 10);  // ...nor a square
    EXPECT_EQ(green, opaque);
    // The stalk is at the bottom centre (v = 1, where the card meets the twig), the corners clear.
    EXPECT_EQ(leaf.at(32, 62)[3], 255);
    EXPECT_EQ(leaf.at(1, 1)[3], 0);
    EXPECT_EQ(leaf.at(62, 62)[3], 0);

    // Every LOD's leaf cards carry one UV per vertex, each card the unit square, base at v = 1.
    for (int node = 0; node < 2; ++node) {
        const auto& primitive = doc["meshes"][doc["nodes"][node]["mesh"].get<int>()]["primitives"][1];
        EXPECT_EQ(primitive["material"], 2);
        const auto& uv = doc["accessors"][primitive["attributes"]["TEXCOORD_0"].get<int>()];
        const auto& position = doc["accessors"][primitive["attributes"]["POSITION"].get<int>()];
        EXPECT_EQ(uv["type"], "VEC2");
        ASSERT_EQ(uv["count"], position["count"]);
        const std::string bytes = view_bytes(glb, doc, uv["bufferView"].get<int>());
        std::vector<float> values(bytes.size() / 4);
        std::memcpy(values.data(), bytes.data(), bytes.size());
        ASSERT_EQ(values.size() % 8, 0u);
        for (std::size_t quad = 0; quad < values.size(); quad += 8)
            EXPECT_EQ(std::vector<float>(values.begin() + quad, values.begin() + quad + 8), (std::vector<float>{0, 1, 1, 1, 1, 0, 0, 0}));
    }
    // Lobes are not textured: no image, no texture coordinates.
    const auto lobed = json_chunk(glb_bytes({gltf_tree(tree_with_lobes({0, 0, 0}), 1)}, {0, 0, 0}));
    EXPECT_FALSE(lobed.contains("images"));
    EXPECT_FALSE(lobed.contains("textures"));
    EXPECT_EQ(lobed["materials"].size(), 2u);
}
