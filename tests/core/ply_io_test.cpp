#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>

using namespace treelobes;
using treelobes::test::error_code_of;
using treelobes::test::TempDir;
using treelobes::test::write_text;

namespace {

PointCloud sample_cloud() {
    PointCloud cloud;
    cloud.positions = {{0, 0, 0}, {1.5f, -2.25f, 3}, {0.001f, 0.002f, 0.003f}};
    cloud.intensity = {1, 2, 65535};
    cloud.classification = {2, 5, 1};
    cloud.rgb = {{{255, 0, 0}}, {{0, 255, 0}}, {{0, 0, 255}}};
    cloud.add_extra("geodesic", AttributeType::Float32).values = {0.5, 1.5, 2.5};
    cloud.add_extra("internode", AttributeType::Int32).values = {0, 7, -1};
    return cloud;
}

void expect_same(const PointCloud& a, const PointCloud& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT((a.global(i) - b.global(i)).norm(), 1e-6);
    EXPECT_EQ(a.intensity, b.intensity);
    EXPECT_EQ(a.classification, b.classification);
    EXPECT_EQ(a.rgb, b.rgb);
    ASSERT_EQ(a.extras.size(), b.extras.size());
    for (std::size_t k = 0; k < a.extras.size(); ++k) {
        EXPECT_EQ(a.extras[k].name, b.extras[k].name);
        EXPECT_EQ(a.extras[k].values, b.extras[k].values);
    }
}

}  // namespace

TEST(PlyCloud, BinaryAndAsciiRoundTripKeepScalarFields) {
    TempDir dir;
    const PointCloud cloud = sample_cloud();
    write_ply_cloud(cloud, dir / "b.ply", true);
    write_ply_cloud(cloud, dir / "a.ply", false);
    expect_same(cloud, read_point_cloud(dir / "b.ply"));
    expect_same(cloud, read_point_cloud(dir / "a.ply"));
    // CloudCompare convention: scalar fields are stored as scalar_<name>.
    const std::string text = read_file(dir / "a.ply");
    EXPECT_NE(text.find("property float scalar_geodesic"), std::string::npos);
    EXPECT_NE(text.find("property int scalar_internode"), std::string::npos);
}

TEST(PlyCloud, ReadsAnyPropertyOrderAndBigEndian) {
    TempDir dir;
    write_text(dir / "order.ply",
               "ply\nformat ascii 1.0\nelement vertex 2\nproperty float scalar_w\nproperty double z\n"
               "property float x\nproperty float y\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
               "9 3 1 2\n8 6 4 5\n");
    const PointCloud cloud = read_point_cloud(dir / "order.ply");
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_FLOAT_EQ(cloud.positions[1].x(), 4);
    EXPECT_FLOAT_EQ(cloud.positions[1].z(), 6);
    EXPECT_DOUBLE_EQ(cloud.extra("w")->values[0], 9);

    std::string be =
            "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    for (float v : {1.0f, 2.0f, 3.0f}) {
        std::uint32_t bits;
        std::memcpy(&bits, &v, 4);
        for (int shift = 24; shift >= 0; shift -= 8) be.push_back(static_cast<char>((bits >> shift) & 0xff));
    }
    write_text(dir / "be.ply", be);
    EXPECT_FLOAT_EQ(read_point_cloud(dir / "be.ply").positions[0].y(), 2.0f);
}

TEST(PlyCloud, TruncatedOrLyingHeadersAreRejected) {
    TempDir dir;
    write_ply_cloud(sample_cloud(), dir / "ok.ply", true);
    const std::string bytes = read_file(dir / "ok.ply");
    write_text(dir / "truncated.ply", bytes.substr(0, bytes.size() - 5));
    EXPECT_EQ(error_code_of([&] { read_point_cloud(dir / "truncated.ply"); }), ExitCode::InvalidInput);

    write_text(dir / "huge.ply",
               "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\n"
               "property float y\nproperty float z\nend_header\n");
    EXPECT_EQ(error_code_of([&] { read_point_cloud(dir / "huge.ply"); }), ExitCode::InvalidInput);
    write_text(dir / "noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
    EXPECT_EQ(error_code_of([&] { read_point_cloud(dir / "noend.ply"); }), ExitCode::InvalidInput);
    write_text(dir / "garbage.ply",
               "\x7f"
               "ELF\x02\x01 binary garbage");
    EXPECT_EQ(error_code_of([&] { read_point_cloud(dir / "garbage.ply"); }), ExitCode::InvalidInput);
    write_text(dir / "nan.ply",
               "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
               "end_header\nnan 0 0\n1 2 3\n");
    const PointCloud kept = read_point_cloud(dir / "nan.ply");
    EXPECT_EQ(kept.size(), 1u);
    EXPECT_EQ(kept.source.dropped_non_finite, 1u);
}

TEST(PlyCloud, UtmOriginSurvivesRoundTripAndWritesSidecar) {
    TempDir dir;
    PointCloud cloud;
    cloud.origin = {650000.0, 5800000.0, 0.0};
    cloud.positions = {{0.1234f, 0.5678f, 101.25f}, {10.0001f, 20.9999f, 99.5f}};
    write_point_cloud(cloud, dir / "utm.ply");
    EXPECT_TRUE(std::filesystem::exists(georef_sidecar_path(dir / "utm.ply")));
    const PointCloud back = read_point_cloud(dir / "utm.ply");
    EXPECT_LT((back.global(1) - cloud.global(1)).norm(), 1e-3);
    EXPECT_NEAR(back.global(0).x(), 650000.1234, 1e-3);
}

TEST(PlyCloud, UnwritableOutputIsAnInputErrorAndLeavesNothing) {
    TempDir dir;
    EXPECT_EQ(error_code_of([&] { write_point_cloud(sample_cloud(), dir / "missing" / "a.ply"); }), ExitCode::InvalidInput);
    std::filesystem::create_directory(dir / "folder.ply");
    EXPECT_EQ(error_code_of([&] { write_point_cloud(sample_cloud(), dir / "folder.ply"); }), ExitCode::InvalidInput);
    EXPECT_EQ(error_code_of([&] { write_point_cloud(sample_cloud(), dir / "a.unknown"); }), ExitCode::Usage);
    // Nothing but the folder we made: no partial output, no temporary files.
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()), 1);
}

TEST(SkeletonPly, RoundTripKeepsTopologyRadiiAndChildOrder) {
    TempDir dir;
    TreeGraph tree;
    tree.origin = {1000.5, 2000.25, 3.0};
    tree.add_node({0, 0, 0}, 0.3f, -1);
    tree.add_node({0, 0, 1}, 0.25f, 0);
    tree.add_node({0.5f, 0, 1.5f}, 0.1f, 1);  // lateral listed first on purpose
    tree.add_node({0, 0, 2}, 0.2f, 1);
    tree.nodes[1].children = {3, 2};  // main child first
    write_skeleton_ply(tree, dir / "s.ply");
    const TreeGraph back = read_skeleton_ply(dir / "s.ply");
    ASSERT_EQ(back.size(), 4u);
    EXPECT_EQ(back.nodes[1].children, (std::vector<int>{3, 2}));
    EXPECT_FLOAT_EQ(back.nodes[2].radius, 0.1f);
    EXPECT_EQ(back.origin, tree.origin);
    EXPECT_EQ(back.nodes[3].parent, 1);
}

TEST(SkeletonPly, AcceptsUnorientedEdgesAndRejectsCyclesAndForests) {
    TempDir dir;
    const std::string header =
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element edge 2\nproperty int vertex1\nproperty int vertex2\nend_header\n0 0 0\n0 0 1\n0 0 2\n";
    write_text(dir / "unoriented.ply", header + "1 0\n2 1\n");
    const TreeGraph tree = read_skeleton_ply(dir / "unoriented.ply");
    EXPECT_EQ(tree.nodes[2].parent, 1);
    write_text(dir / "cycle.ply", header + "0 1\n1 0\n");
    EXPECT_EQ(error_code_of([&] { read_skeleton_ply(dir / "cycle.ply"); }), ExitCode::InvalidInput);
    write_text(dir / "bad_index.ply", header + "0 1\n1 7\n");
    EXPECT_EQ(error_code_of([&] { read_skeleton_ply(dir / "bad_index.ply"); }), ExitCode::InvalidInput);
}

TEST(MeshIo, PlyObjOffRoundTrip) {
    TempDir dir;
    TriangleMesh mesh;  // a tetrahedron, outward oriented
    mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    mesh.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (const char* name : {"t.ply", "t.obj", "t.off"}) {
        write_mesh(mesh, dir / name);
        const TriangleMesh back = read_mesh(dir / name);
        EXPECT_EQ(back.vertex_count(), 4u) << name;
        EXPECT_EQ(back.face_count(), 4u) << name;
        EXPECT_NEAR(back.signed_volume(), 1.0 / 6.0, 1e-6) << name;
    }
    write_text(dir / "empty.off", "");
    EXPECT_EQ(error_code_of([&] { read_mesh(dir / "empty.off"); }), ExitCode::InvalidInput);
}

TEST(MeshIo, NonManifoldFacesAreKeptNotDropped) {
    TempDir dir;
    TriangleMesh mesh;  // three triangles sharing one edge: not representable as a halfedge mesh
    mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
    mesh.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
    write_mesh(mesh, dir / "nm.ply");
    EXPECT_EQ(read_mesh(dir / "nm.ply").face_count(), 3u);
}

TEST(PcdIo, RoundTripWithIntensityAndExtras) {
    TempDir dir;
    PointCloud cloud;
    cloud.positions = {{1, 2, 3}, {4, 5, 6}};
    cloud.intensity = {7, 8};
    cloud.add_extra("label", AttributeType::Float32, 3.0);
    write_point_cloud(cloud, dir / "c.pcd");
    const PointCloud back = read_point_cloud(dir / "c.pcd");
    ASSERT_EQ(back.size(), 2u);
    EXPECT_FLOAT_EQ(back.positions[1].z(), 6);
    EXPECT_EQ(back.intensity, cloud.intensity);
    ASSERT_NE(back.extra("label"), nullptr);
    write_text(dir / "bad.pcd",
               "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
               "WIDTH 100\nHEIGHT 1\nPOINTS 100\nDATA binary\nabc");
    EXPECT_EQ(error_code_of([&] { read_point_cloud(dir / "bad.pcd"); }), ExitCode::InvalidInput);
}

// Fuzzing found these (UBSan: a NaN or out-of-range double cast to an integer attribute;
// ASan: PCL's reader crashing on an empty file). Attributes clamp, NaN is "no value" (0).
TEST(PlyCloud, NanAndOutOfRangeIntegerAttributesClamp) {
    TempDir dir;
    write_text(dir / "a.ply",
               "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
               "property float z\nproperty float intensity\nproperty float classification\n"
               "property float red\nproperty float green\nproperty float blue\nend_header\n"
               "0 0 0 nan 300 -5 nan 70000\n1 1 1 12.7 2 1 2 3\n");
    const PointCloud cloud = read_ply_cloud(dir / "a.ply");
    ASSERT_EQ(cloud.size(), 2u);
    EXPECT_EQ(cloud.intensity, (std::vector<std::uint16_t>{0, 12}));
    EXPECT_EQ(cloud.classification, (std::vector<std::uint8_t>{255, 2}));
    ASSERT_EQ(cloud.rgb.size(), 2u);
    EXPECT_EQ(cloud.rgb[0], (std::array<std::uint16_t, 3>{0, 0, 65535}));
}

TEST(Pcd, EmptyFileIsBadInputNotACrash) {
    TempDir dir;
    write_text(dir / "empty.pcd", "");
    EXPECT_EQ(error_code_of([&] { read_pcd(dir / "empty.pcd"); }), ExitCode::InvalidInput);
}

// Fuzzing found both: PCL's PCD reader crashed on a header without its FIELDS line, OpenMesh's
// PLY reader never returned on a header without end_header.
TEST(Pcd, HeaderWithoutFieldsIsBadInputNotACrash) {
    TempDir dir;
    write_text(dir / "nofields.pcd",
               "# .PCD v0.7\nVERSION 0.7\nFIEL S x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
               "WIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n");
    EXPECT_EQ(error_code_of([&] { read_pcd(dir / "nofields.pcd"); }), ExitCode::InvalidInput);
}

// Fuzzing found it in CI: "SIZE 4 z 4 ..." gave y a field type PCL could not name, which the
// reader took for 8-byte doubles and read past the point record.
TEST(Pcd, FieldWithoutAValidSizeIsBadInputNotAnOverflow) {
    EXPECT_EQ(error_code_of([&] { read_pcd(test::source_dir() / "tests/data/fuzz/pcd_field_outside_record.pcd"); }),
              ExitCode::InvalidInput);
}

// Found by fuzzing in CI: a format line whose version is not a number left OpenMesh's header loop
// spinning on a failed stream.
TEST(MeshRead, PlyFormatVersionNotANumberIsBadInputNotAHang) {
    EXPECT_EQ(error_code_of([&] { read_mesh(test::source_dir() / "tests/data/fuzz/ply_format_version_not_a_number.ply"); }),
              ExitCode::InvalidInput);
}

// Found by fuzzing in CI: OpenMesh reads the version into a float and its header word by word, so
// a version of nan, inf or beyond a float, and an obj_info line naming a header keyword, left it
// spinning on a failed stream (or, for "property" before any element, crashed it).
TEST(MeshRead, PlyHeadersOpenMeshMisreadsAreBadInputNotAHang) {
    TempDir dir;
    const std::string elements =
            "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    const std::map<std::string, std::string> misread{
            {"version_nan.ply", "ply\nformat ascii nan\n" + elements},
            {"version_inf.ply", "ply\nformat ascii inf\n" + elements},
            {"version_beyond_float.ply", "ply\nformat ascii 1e39\n" + elements},
            {"obj_info_element.ply", "ply\nformat ascii 1.0\nobj_info element\n" + elements},
            {"obj_info_property.ply", "ply\nformat ascii 1.0\nobj_info property list uchar int a\n" + elements},
            {"obj_info_end_header.ply", "ply\nformat ascii 1.0\nobj_info end_header\n" + elements},
    };
    for (const auto& [file, text] : misread) {
        const auto path = dir / file;  // clang 14 (the sanitizer build) cannot capture a structured binding
        write_text(path, text);
        EXPECT_EQ(error_code_of([&] { read_mesh(path); }), ExitCode::InvalidInput) << file;
    }
    write_text(dir / "plain.ply", "ply\nformat ascii 1.0\nobj_info scanned by a test\n" + elements);
    EXPECT_EQ(read_mesh(dir / "plain.ply").faces.size(), 1u);
}

// Found by fuzzing: OpenMesh's OFF reader asked for 1.6 GB on a small OFF file whose vertex lines
// were damaged (and, after a header check, again on another), so OFF has its own reader.
TEST(MeshRead, DamagedOffIsBadInput) {
    TempDir dir;
    const std::string vertices = "OFF\n3 1 0\n0 0 0\n1 0 0\n";
    const std::map<std::string, std::string> damaged{
            {"vertex.off", vertices + "0 1 0-05 x\n3 0 1 2\n"},
            {"nan.off", vertices + "0 nan 0\n3 0 1 2\n"},
            {"count.off", "OFF\n99999999 1 0\n0 0 0\n"},
            {"negative.off", "OFF\n3 -1 0\n0 0 0\n1 0 0\n0 1 0\n"},
            {"no_face_count.off", "OFF\n3\n0 0 0\n1 0 0\n0 1 0\n"},
            {"corner.off", vertices + "0 1 0\n3 0 1 7\n"},
            {"huge_corner_count.off", vertices + "0 1 0\n18446744073709551615 0 1 2\n"},
            {"short_face.off", vertices + "0 1 0\n4 0 1 2\n"},
            {"two_corners.off", vertices + "0 1 0\n2 0 1\n"},
            {"truncated.off", vertices + "0 1 0\n"},
            {"binary.off", "OFF BINARY\n3 1 0\n"},
            {"four_d.off", "4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n"},
            {"not_off.off", "ply\nformat ascii 1.0\n"},
    };
    for (const auto& [file, text] : damaged) {
        const auto path = dir / file;  // clang 14 (the sanitizer build) cannot capture a structured binding
        write_text(path, text);
        EXPECT_EQ(error_code_of([&] { read_mesh(path); }), ExitCode::InvalidInput) << file;
    }
}

// Colours, normals and comments are skipped, the counts may follow the keyword, polygons become
// fans and a face with a repeated corner is dropped and counted.
TEST(MeshRead, OffVariantsAreRead) {
    TempDir dir;
    write_text(dir / "plain.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(read_mesh(dir / "plain.off").faces.size(), 1u);
    write_text(dir / "coloured.off",
               "# a comment\nCNOFF 5 3 0\n"
               "0 0 0  0 0 1  255 0 0 255\n1 0 0  0 0 1  0 255 0 255\n1 1 0 0 0 1 0 0 255 255\n"
               "0 1 0 0 0 1 9 9 9 255  # trailing comment\n\n5000 5000 5000 0 0 1 1 1 1 255\n"
               "4 0 1 2 3  0.5 0.5 0.5\n3 0 0 4\n3 2 3 4\n");
    const NamedMesh mesh = read_named_mesh(dir / "coloured.off");
    EXPECT_EQ(mesh.mesh.vertex_count(), 5u);
    EXPECT_EQ(mesh.mesh.face_count(), 3u);
    EXPECT_EQ(mesh.report.polygons_split, 1u);
    EXPECT_EQ(mesh.report.degenerate_faces, 1u);
    EXPECT_EQ(mesh.mesh.faces[2], (std::array<int, 3>{2, 3, 4}));
    write_text(dir / "utm.off", "OFF\n3 1 0\n512345.25 5400123.5 301\n512346.25 5400123.5 301\n512345.25 5400124.5 301\n3 0 1 2\n");
    const TriangleMesh utm = read_mesh(dir / "utm.off");
    EXPECT_EQ(utm.origin, Eigen::Vector3d(512000, 5400000, 0));
    EXPECT_FLOAT_EQ(utm.vertices[1].x(), 346.25f);
}

TEST(Pcd, GarbageHeaderLineIsBadInputNotACrash) {
    TempDir dir;
    const std::string garbage = std::string("\xd7\xa3\xbb") + '\0' + "F";  // bytes of the fuzzer's input
    write_text(dir / "garbage.pcd", "# .PCD v0.7\n" + garbage +
                                            "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                                            "WIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n");
    EXPECT_EQ(error_code_of([&] { read_pcd(dir / "garbage.pcd"); }), ExitCode::InvalidInput);
}

TEST(MeshRead, PlyHeaderWithoutEndIsBadInputNotAHang) {
    TempDir dir;
    write_text(dir / "open.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n0 0 0\n");
    EXPECT_EQ(error_code_of([&] { read_mesh(dir / "open.ply"); }), ExitCode::InvalidInput);
}

// Found by the 60-second fuzz runs with seed 1: PCL threw std::length_error from inside its
// reader on a COUNT of "1%" (an internal error, exit 4, instead of bad input).
TEST(Pcd, HeaderValueThatIsNotANumberIsBadInput) {
    EXPECT_EQ(error_code_of([&] { read_pcd(test::source_dir() / "tests/data/fuzz/pcd_count_not_a_number.pcd"); }), ExitCode::InvalidInput);
    TempDir dir;
    write_text(dir / "type.pcd",
               "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F Q\nCOUNT 1 1 1\n"
               "WIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n");
    EXPECT_EQ(error_code_of([&] { read_pcd(dir / "type.pcd"); }), ExitCode::InvalidInput);
    // The second finding of those runs: PCL threw from inside its header parser on repeated and
    // overlapping header lines.
    EXPECT_EQ(error_code_of([&] { read_pcd(test::source_dir() / "tests/data/fuzz/pcd_header_repeated_lines.pcd"); }),
              ExitCode::InvalidInput);
    // The third: NUL bytes in the FIELDS line made PCL use memory it had freed (ASan).
    EXPECT_EQ(error_code_of([&] { read_pcd(test::source_dir() / "tests/data/fuzz/pcd_fields_line_with_nul_bytes.pcd"); }),
              ExitCode::InvalidInput);
}

// Found by the 60-second fuzz runs with seed 1: OpenMesh's PLY reader wrote through a null
// pointer (SEGV) on a property declared before any element; unknown property types are refused too.
TEST(MeshRead, PlyElementCountBeyondTheFileIsBadInputNotAnAllocation) {
    EXPECT_EQ(error_code_of([&] { read_mesh(test::source_dir() / "tests/data/fuzz/ply_element_count_beyond_file.ply"); }),
              ExitCode::InvalidInput);
    TempDir dir;
    write_text(dir / "many.ply",
               "ply\nformat ascii 1.0\nelement vertex 3000\nproperty float x\nproperty float y\nproperty float z\n"
               "end_header\n0 0 0\n");
    EXPECT_EQ(error_code_of([&] { read_mesh(dir / "many.ply"); }), ExitCode::InvalidInput);
}

TEST(MeshRead, PlyPropertyBeforeAnyElementIsBadInputNotACrash) {
    EXPECT_EQ(error_code_of([&] { read_mesh(test::source_dir() / "tests/data/fuzz/ply_property_before_element.ply"); }),
              ExitCode::InvalidInput);
    TempDir dir;
    write_text(dir / "type.ply",
               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty real z\n"
               "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(error_code_of([&] { read_mesh(dir / "type.ply"); }), ExitCode::InvalidInput);
    write_text(dir / "good.ply",
               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
               "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(read_mesh(dir / "good.ply").faces.size(), 1u);
}
