// Mesh files as CG tree models come: OBJ with objects, groups and materials, polygons, negative
// and slash-separated corners, degenerate faces, UTM-sized coordinates; PLY with non-manifold
// edges through OpenMesh; broken files rejected with one line naming the file.
#include "core/mesh_io.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace treelobes;
using test::TempDir;
using test::write_text;

namespace {

const char* kPartsObj =
        "# two parts\n"
        "o Tree\n"
        "g Trunk\n"
        "usemtl Bark\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
        "vn 0 0 1\n"
        "f 1 2 3 4\n"  // a quad: two triangles
        "usemtl Leaf\n"
        "v 0 0 1\nv 1 0 1\nv 0.5 1 1\n"
        "f -3/1/1 -2/1/1 -1/1/1\n"
        "f 5 5 6\n";  // degenerate: dropped

}  // namespace

TEST(MeshIo, ObjKeepsObjectGroupAndMaterialPerFace) {
    TempDir dir;
    write_text(dir / "parts.obj", kPartsObj);
    const NamedMesh m = read_named_mesh(dir / "parts.obj");
    ASSERT_EQ(m.mesh.faces.size(), 3u);
    EXPECT_EQ(m.mesh.vertices.size(), 7u);
    EXPECT_EQ(m.report.format, "obj");
    EXPECT_EQ(m.report.polygons_split, 1u);
    EXPECT_EQ(m.report.degenerate_faces, 1u);
    EXPECT_EQ(m.report.normals_ignored, 1u);
    ASSERT_EQ(m.face_names.size(), 3u);
    ASSERT_EQ(m.names.size(), 2u);
    EXPECT_EQ(m.names[m.face_names[0]], (FaceNames{"Bark", "Trunk", "Tree"}));
    EXPECT_EQ(m.face_names[0], m.face_names[1]);
    EXPECT_EQ(m.names[m.face_names[2]], (FaceNames{"Leaf", "Trunk", "Tree"}));
    // Negative corners count back from the last vertex read.
    EXPECT_EQ(m.mesh.faces[2], (std::array<int, 3>{4, 5, 6}));
}

TEST(MeshIo, ObjWithoutNamesHasNoFaceNames) {
    TempDir dir;
    write_text(dir / "plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const NamedMesh m = read_named_mesh(dir / "plain.obj");
    EXPECT_EQ(m.mesh.faces.size(), 1u);
    EXPECT_TRUE(m.face_names.empty());
    EXPECT_TRUE(m.names.empty());
}

TEST(MeshIo, UtmCoordinatesKeepMillimetres) {
    TempDir dir;
    write_text(dir / "utm.obj",
               "v 500123.456 5600000.789 300.5\nv 500124.457 5600000.789 300.5\nv 500123.456 5600001.790 301.5\nf 1 2 3\n");
    const TriangleMesh m = read_mesh(dir / "utm.obj");
    EXPECT_EQ(m.origin, Eigen::Vector3d(500000, 5600000, 0));
    const Eigen::Vector3d second = m.origin + m.vertices[1].cast<double>();
    EXPECT_NEAR(second.x(), 500124.457, 1e-3);
    EXPECT_NEAR(second.y(), 5600000.789, 1e-3);
}

TEST(MeshIo, BrokenObjFilesAreRejectedWithTheLine) {
    TempDir dir;
    const std::pair<const char*, const char*> cases[] = {
            {"truncated_face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2"},
            {"truncated_vertex.obj", "v 0 0 0\nv 1 0"},
            {"missing_vertex.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"},
            {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"},
            {"garbage.obj", "v 0 0 0\n\x01\x02\x03 binary\n"},
            {"no_vertices.obj", "# nothing\n"},
    };
    for (const auto& [name, text] : cases) {
        write_text(dir / name, text);
        try {
            read_named_mesh(dir / name);
            ADD_FAILURE() << name << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput) << name;
            const std::string message = e.what();
            EXPECT_NE(message.find(name), std::string::npos) << message;
            EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        }
    }
    write_text(dir / "empty.obj", "");
    EXPECT_EQ(test::error_code_of([&] { read_named_mesh(dir / "empty.obj"); }), ExitCode::InvalidInput);
    EXPECT_EQ(test::error_code_of([&] { read_named_mesh(dir / "absent.ply"); }), ExitCode::InvalidInput);
}

TEST(MeshIo, PlyWithNonManifoldEdgeKeepsEveryFace) {
    TempDir dir;
    // Three triangles around one edge (0-1): a fin no halfedge mesh can hold as is.
    write_text(dir / "fin.ply",
               "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
               "element face 3\nproperty list uchar int vertex_indices\nend_header\n"
               "0 0 0\n1 0 0\n0.5 1 0\n0.5 -1 0\n0.5 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n");
    const NamedMesh m = read_named_mesh(dir / "fin.ply");
    EXPECT_EQ(m.mesh.faces.size(), 3u);
    EXPECT_NEAR(m.mesh.area(), 1.5, 1e-6);
    EXPECT_TRUE(m.face_names.empty());
}

TEST(MeshIo, NamedObjRoundTrip) {
    TempDir dir;
    write_text(dir / "parts.obj", kPartsObj);
    const NamedMesh m = read_named_mesh(dir / "parts.obj");
    write_named_mesh(m, dir / "copy.obj");
    const NamedMesh back = read_named_mesh(dir / "copy.obj");
    ASSERT_EQ(back.mesh.faces.size(), m.mesh.faces.size());
    ASSERT_EQ(back.face_names.size(), m.face_names.size());
    for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
        EXPECT_EQ(back.names[back.face_names[f]], m.names[m.face_names[f]]);
        for (int c = 0; c < 3; ++c) EXPECT_EQ(back.mesh.vertices[back.mesh.faces[f][c]], m.mesh.vertices[m.mesh.faces[f][c]]);
    }
}
