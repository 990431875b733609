// glTF 2.0 binaries as other tools write them, made by hand (tests/support/glb_builder.hpp):
// two nodes (translation/rotation/scale and a matrix with a child), indexed u8/u16/u32 and
// non-indexed primitives, a strip, a fan, quantized positions, a lines primitive, material names;
// positions back in our z-up frame; damaged and unsupported files rejected with one line.
#include "core/georef_sidecar.hpp"
#include "core/mesh_io.hpp"
#include "support/glb_builder.hpp"
#include "support/test_support.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>

using namespace treelobes;
using nlohmann::json;
using test::GlbBuilder;
using test::TempDir;

namespace {

using Points = std::vector<Eigen::Vector3f>;

// Node 0 "TreeA": T (1, 2, 3), R 90 degrees about glTF's +y, S 2, mesh "Trunk" with
//   - Bark: a quad as u16 triangles, plus one degenerate triangle;
//   - Leaf: a u32-indexed strip of 4 vertices (2 triangles).
// Node 1 "Group": a matrix translating by (10, 0, 0), child node 2 "Child" translated (0, 1, 0)
// with mesh "Crown":
//   - Leaf: a non-indexed fan of 5 vertices (3 triangles);
//   - Bark: SHORT normalized positions (KHR_mesh_quantization, stride 8), u8 indices;
//   - a LINES primitive (skipped).
GlbBuilder two_trees() {
    GlbBuilder b;
    const int quad = b.positions({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
    const int quad_indices = b.accessor<std::uint16_t>({0, 1, 2, 0, 2, 3, 0, 0, 1}, GlbBuilder::kUnsignedShort, "SCALAR");
    const int strip = b.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}});
    const int strip_indices = b.accessor<std::uint32_t>({0, 1, 2, 3}, GlbBuilder::kUnsignedInt, "SCALAR");
    const int fan = b.positions({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {-1, 1, 0}});
    const int quantized = b.accessor<std::int16_t>({32767, 0, 0, 0, 32767, 0, 0, 0, -32768}, GlbBuilder::kShort, "VEC3", 8, true);
    const int quantized_indices = b.accessor<std::uint8_t>({0, 1, 2}, GlbBuilder::kUnsignedByte, "SCALAR");
    b.doc["materials"] = {{{"name", "Bark"}}, {{"name", "Leaf"}}};
    b.mesh("Trunk", {{{"attributes", {{"POSITION", quad}}}, {"indices", quad_indices}, {"material", 0}},
                     {{"attributes", {{"POSITION", strip}}}, {"indices", strip_indices}, {"material", 1}, {"mode", 5}}});
    b.mesh("Crown", {{{"attributes", {{"POSITION", fan}}}, {"material", 1}, {"mode", 6}},
                     {{"attributes", {{"POSITION", quantized}}}, {"indices", quantized_indices}, {"material", 0}, {"mode", 4}},
                     {{"attributes", {{"POSITION", fan}}}, {"mode", 1}}});
    const double half = std::sqrt(0.5);
    b.doc["nodes"] = {{{"name", "TreeA"}, {"mesh", 0}, {"translation", {1, 2, 3}}, {"rotation", {0, half, 0, half}}, {"scale", {2, 2, 2}}},
                      {{"name", "Group"}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1}}, {"children", {2}}},
                      {{"name", "Child"}, {"mesh", 1}, {"translation", {0, 1, 0}}}};
    b.doc["scenes"][0]["nodes"] = {0, 1};
    return b;
}

std::filesystem::path write_glb(const TempDir& dir, const std::string& name, const std::string& bytes) {
    test::write_text(dir / name, bytes);
    return dir / name;
}

Eigen::Vector3d world(const TriangleMesh& mesh, int vertex) {
    return mesh.origin + mesh.vertices[static_cast<std::size_t>(vertex)].cast<double>();
}

// The message of the InvalidInput error reading `path` throws (a failure when it throws none).
std::string input_error(const std::filesystem::path& path) {
    try {
        read_named_mesh(path);
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput) << e.what();
        const std::string message = e.what();
        EXPECT_NE(message.find(path.string()), std::string::npos) << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        return message;
    }
    ADD_FAILURE() << path << " was accepted";
    return {};
}

}  // namespace

TEST(GlbMeshRead, NodesPrimitivesAndNamesInOurFrame) {
    TempDir dir;
    const NamedMesh m = read_named_mesh(write_glb(dir, "trees.glb", two_trees().bytes()));
    EXPECT_EQ(m.report.format, "glb");
    EXPECT_EQ(m.report.degenerate_faces, 1u);
    EXPECT_EQ(m.report.primitives_skipped, 1u);
    ASSERT_EQ(m.mesh.vertices.size(), 4u + 4u + 5u + 3u);
    ASSERT_EQ(m.mesh.faces.size(), 2u + 2u + 3u + 1u);
    EXPECT_EQ(m.mesh.origin, Eigen::Vector3d::Zero());

    // Node 0: glTF (1, 0, 0) -> S (2, 0, 0) -> R (0, 0, -2) -> T (1, 2, 1), z-up (1, -1, 2).
    EXPECT_TRUE(world(m.mesh, 1).isApprox(Eigen::Vector3d(1, -1, 2), 1e-6)) << world(m.mesh, 1).transpose();
    // glTF (0, 1, 0) -> (0, 2, 0) -> (0, 2, 0) -> (1, 4, 3), z-up (1, -3, 4).
    EXPECT_TRUE(world(m.mesh, 3).isApprox(Eigen::Vector3d(1, -3, 4), 1e-6)) << world(m.mesh, 3).transpose();
    // Node 2 under node 1: fan vertex 4 (-1, 1, 0) + (0, 1, 0) + (10, 0, 0) = (9, 2, 0), z-up (9, 0, 2).
    EXPECT_TRUE(world(m.mesh, 8 + 4).isApprox(Eigen::Vector3d(9, 0, 2), 1e-6)) << world(m.mesh, 12).transpose();
    // Quantized (0, 0, -32768) is -1 (clamped): (10, 1, -1), z-up (10, 1, 1).
    EXPECT_TRUE(world(m.mesh, 13 + 2).isApprox(Eigen::Vector3d(10, 1, 1), 1e-6)) << world(m.mesh, 15).transpose();
    EXPECT_TRUE(world(m.mesh, 13).isApprox(Eigen::Vector3d(11, 0, 1), 1e-6)) << world(m.mesh, 13).transpose();

    using Face = std::array<int, 3>;
    EXPECT_EQ(m.mesh.faces[0], (Face{0, 1, 2}));
    EXPECT_EQ(m.mesh.faces[1], (Face{0, 2, 3}));
    EXPECT_EQ(m.mesh.faces[2], (Face{4, 5, 6}));   // strip: {0, 1, 2}
    EXPECT_EQ(m.mesh.faces[3], (Face{5, 7, 6}));   // strip: {1, 3, 2}
    EXPECT_EQ(m.mesh.faces[4], (Face{9, 10, 8}));  // fan: {1, 2, 0}
    EXPECT_EQ(m.mesh.faces[6], (Face{11, 12, 8}));
    EXPECT_EQ(m.mesh.faces[7], (Face{13, 14, 15}));

    ASSERT_EQ(m.face_names.size(), m.mesh.faces.size());
    const auto names = [&](std::size_t face) { return m.names[m.face_names[face]]; };
    EXPECT_EQ(names(0), (FaceNames{"Bark", "Trunk", "TreeA"}));
    EXPECT_EQ(names(2), (FaceNames{"Leaf", "Trunk", "TreeA"}));
    EXPECT_EQ(names(4), (FaceNames{"Leaf", "Crown", "Child"}));
    EXPECT_EQ(names(7), (FaceNames{"Bark", "Crown", "Child"}));
    EXPECT_EQ(m.names.size(), 4u);
}

TEST(GlbMeshRead, WithoutScenesEveryRootNodeIsRead) {
    TempDir dir;
    GlbBuilder b = two_trees();
    b.doc.erase("scene");
    b.doc.erase("scenes");
    EXPECT_EQ(read_mesh(write_glb(dir, "library.glb", b.bytes())).faces.size(), 8u);
    b.doc["scenes"] = {{{"nodes", {1}}}};  // no `scene`: the first scene
    EXPECT_EQ(read_mesh(write_glb(dir, "first.glb", b.bytes())).faces.size(), 4u);
}

TEST(GlbMeshRead, MirroringTransformKeepsFacesCounterClockwise) {
    TempDir dir;
    GlbBuilder b;
    const int triangle = b.positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    b.mesh("m", {{{"attributes", {{"POSITION", triangle}}}}});
    b.doc["nodes"] = {{{"mesh", 0}}, {{"mesh", 0}, {"scale", {-1, 1, 1}}}};
    b.doc["scenes"][0]["nodes"] = {0, 1};
    const TriangleMesh m = read_mesh(write_glb(dir, "mirror.glb", b.bytes()));
    ASSERT_EQ(m.faces.size(), 2u);
    const auto normal = [&](const std::array<int, 3>& f) {
        return (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]).normalized();
    };
    EXPECT_TRUE(normal(m.faces[0]).isApprox(normal(m.faces[1]), 1e-6f));  // glTF +z faces, our -y
}

TEST(GlbMeshRead, GeorefSidecarOriginIsAddedBack) {
    TempDir dir;
    const auto path = write_glb(dir, "utm.glb", two_trees().bytes());
    write_georef_sidecar(path, {500000.0, 5600000.0, 300.0}, {});
    const TriangleMesh m = read_mesh(path);
    EXPECT_EQ(m.origin, Eigen::Vector3d(500000.0, 5600000.0, 300.0));
    EXPECT_TRUE(world(m, 1).isApprox(Eigen::Vector3d(500001, 5599999, 302), 1e-12));
}

TEST(GlbMeshRead, DamagedAndUnsupportedFilesAreRejectedWithOneLine) {
    TempDir dir;
    const std::string good = two_trees().bytes();
    const auto modified = [&](const std::function<void(GlbBuilder&)>& change) {
        GlbBuilder b = two_trees();
        change(b);
        return b.bytes();
    };
    std::string wrong_magic = good;
    wrong_magic[0] = 'x';
    std::string nan_bin = two_trees().bin;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(nan_bin.data() + 4, &nan, 4);  // quad vertex 0, y
    const std::pair<const char*, std::string> cases[] = {
            {"truncated.glb", good.substr(0, good.size() - 10)},
            {"wrong_magic.glb", wrong_magic},
            {"not_json.glb", GlbBuilder::container("{\"asset\": [", two_trees().bin)},
            {"beyond_buffer.glb", modified([](GlbBuilder& b) { b.doc["accessors"][0]["count"] = 1000; })},
            // The quad's u16 indices read from its float positions: 1.0f holds the u16 16256.
            {"index_out_of_range.glb", modified([](GlbBuilder& b) { b.doc["accessors"][1]["bufferView"] = 0; })},
            {"cycle.glb", modified([](GlbBuilder& b) { b.doc["nodes"][2]["children"] = {1}; })},
            {"draco.glb", modified([](GlbBuilder& b) { b.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"}; })},
            {"nan.glb", GlbBuilder::container(two_trees().doc.dump(), nan_bin)},
            {"no_triangles.glb", modified([](GlbBuilder& b) { b.doc["scenes"][0]["nodes"] = json::array(); })},
            {"external.glb", modified([](GlbBuilder& b) { b.doc["buffers"][0]["uri"] = "trees.bin"; })},
            {"sparse.glb", modified([](GlbBuilder& b) {
                 b.doc["accessors"][0]["sparse"] = {{"count", 1}};
             })},
            {"no_bin.glb", GlbBuilder::container(two_trees().doc.dump(), "")},
            {"missing_mesh.glb", modified([](GlbBuilder& b) { b.doc["nodes"][0]["mesh"] = 7; })},
            {"string_index.glb", modified([](GlbBuilder& b) { b.doc["nodes"][0]["mesh"] = "0"; })},
            {"stride.glb", modified([](GlbBuilder& b) { b.doc["bufferViews"][5]["byteStride"] = 4; })},
    };
    for (const auto& [name, bytes] : cases) {
        SCOPED_TRACE(name);
        input_error(write_glb(dir, name, bytes));
    }
    EXPECT_NE(input_error(dir / "draco.glb").find("KHR_draco_mesh_compression"), std::string::npos);
    EXPECT_NE(input_error(dir / "external.glb").find("self-contained .glb"), std::string::npos);
    EXPECT_NE(input_error(dir / "cycle.glb").find("node 1 is reached twice"), std::string::npos);
    EXPECT_NE(input_error(dir / "index_out_of_range.glb").find("beyond the 4 vertices"), std::string::npos);
}

TEST(GlbMeshRead, DeepHierarchyIsRefusedNotRecursedForever) {
    TempDir dir;
    GlbBuilder b = two_trees();
    json nodes = json::array();
    for (int n = 0; n < 5000; ++n) nodes.push_back({{"children", {n + 1}}});
    nodes.push_back({{"mesh", 0}});
    b.doc["nodes"] = nodes;
    b.doc["scenes"][0]["nodes"] = {0};
    EXPECT_NE(input_error(write_glb(dir, "deep.glb", b.bytes())).find("deeper than"), std::string::npos);
}

TEST(GlbMeshRead, InstancingBeyondTheFileSizeIsRefusedNotAllocated) {
    TempDir dir;
    GlbBuilder b = two_trees();
    json nodes = json::array(), roots = json::array();
    for (int n = 0; n < 2000; ++n) {
        nodes.push_back({{"mesh", 1}});
        roots.push_back(n);
    }
    b.doc["nodes"] = nodes;
    b.doc["scenes"][0]["nodes"] = roots;
    // 2000 instances of the crown (8 vertices, 4 triangles) in a file of about 40 kB: a forest.
    EXPECT_EQ(read_mesh(write_glb(dir, "forest.glb", b.bytes())).faces.size(), 2000u * 4u);
    // The same with a strip of 4000 vertices: 8 million vertices from 90 kB, refused before
    // anything is allocated for them.
    const int strip = b.accessor(std::vector<float>(3 * 4000, 0.5f), GlbBuilder::kFloat, "VEC3");
    b.doc["meshes"][1]["primitives"][0]["attributes"]["POSITION"] = strip;
    b.doc["meshes"][1]["primitives"][0]["mode"] = 5;
    EXPECT_NE(input_error(write_glb(dir, "huge.glb", b.bytes())).find("per byte of the file"), std::string::npos);
}
