#include "geometry/closed_mesh.hpp"
#include "lobes/mesh_coder.hpp"
#include "lobes/occupancy.hpp"
#include "lobes/tlobe_io.hpp"

#include "core/error.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>

using namespace treelobes;
using namespace treelobes::lobes;
using treelobes::test::error_code_of;

namespace {

// A closed octahedron around `c` with half-size `r`, outward.
TriangleMesh octahedron(const Eigen::Vector3f& c, float r) {
    TriangleMesh m;
    m.vertices = {c + Eigen::Vector3f(r, 0, 0),  c + Eigen::Vector3f(-r, 0, 0), c + Eigen::Vector3f(0, r, 0),
                  c + Eigen::Vector3f(0, -r, 0), c + Eigen::Vector3f(0, 0, r),  c + Eigen::Vector3f(0, 0, -r)};
    m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    return m;
}

LobeTree sample_tree() {
    LobeTree t;
    t.skeleton.origin = {612345.25, 5812345.5, 101.0};
    t.skeleton.add_node({0, 0, 0}, 0.15f, -1);
    t.skeleton.add_node({0.01f, 0, 1.0f}, 0.12f, 0);
    t.skeleton.add_node({0.3f, -0.2f, 2.0f}, 0.05f, 1);
    t.skeleton.add_node({-0.4f, 0.1f, 1.9f}, 0.04f, 1);
    t.species = "lagerstroemia";
    t.beta = 1.3;
    t.gamma = 1.6;
    t.fs = 0.85;
    t.alpha_factor = 5.0;
    t.root_diameter = 0.3;
    for (int i : {2, 3}) {
        Lobe lobe;
        lobe.mesh = octahedron(t.skeleton.nodes[i].position + Eigen::Vector3f(0, 0, 0.5f), 0.4f + 0.1f * i);
        lobe.seed_node = i;
        lobe.seed_direction = Eigen::Vector3f(0.2f * i, 0.1f, 1.0f).normalized();
        lobe.points = 1000u * i;
        t.lobes.push_back(lobe);
    }
    return t;
}

// The file `bytes` with minor version `minor` and its payload changed by `edit`: inflated,
// edited, deflated, and the header's sizes and CRC-32 made right again (docs/tlobe.md).
template <class Edit>
std::string rewritten(const std::string& bytes, int minor, Edit edit) {
    const auto u32 = [&](std::size_t at) {
        std::uint32_t v = 0;
        for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(bytes[at + k]);
        return v;
    };
    std::string payload(u32(8), '\0');
    uLongf size = payload.size();
    EXPECT_EQ(uncompress(reinterpret_cast<Bytef*>(payload.data()), &size, reinterpret_cast<const Bytef*>(bytes.data() + 20),
                         static_cast<uLong>(bytes.size() - 20)),
              Z_OK);
    edit(payload);
    uLongf packed = compressBound(static_cast<uLong>(payload.size()));
    std::string file(20 + packed, '\0');
    compress(reinterpret_cast<Bytef*>(file.data() + 20), &packed, reinterpret_cast<const Bytef*>(payload.data()),
             static_cast<uLong>(payload.size()));
    file.resize(20 + packed);
    std::copy(bytes.begin(), bytes.begin() + 8, file.begin());
    file[5] = static_cast<char>(minor);
    const auto put = [&](std::size_t at, std::uint32_t v) {
        for (int k = 0; k < 4; ++k) file[at + k] = static_cast<char>((v >> (8 * k)) & 0xff);
    };
    put(8, static_cast<std::uint32_t>(payload.size()));
    put(12, static_cast<std::uint32_t>(packed));
    uLong crc = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(file.data()), 16);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(file.data() + 20), static_cast<uInt>(packed));
    put(16, static_cast<std::uint32_t>(crc));
    return file;
}

}  // namespace

// The faces of `decoded` are those of `original` (each with its corners in the same cyclic
// order), positions within half a quantum.
void expect_same_faces(const TriangleMesh& decoded, const TriangleMesh& original, float half_quantum) {
    ASSERT_EQ(decoded.faces.size(), original.faces.size());
    std::vector<bool> matched(original.faces.size(), false);
    const auto near = [&](int d, int o) {
        return (decoded.vertices[d] - original.vertices[o]).cwiseAbs().maxCoeff() <= half_quantum + 1e-5f;
    };
    for (const auto& f : decoded.faces) {
        bool found = false;
        for (std::size_t g = 0; g < original.faces.size() && !found; ++g)
            for (int r = 0; r < 3 && !found && !matched[g]; ++r)
                if (near(f[0], original.faces[g][r]) && near(f[1], original.faces[g][(r + 1) % 3]) &&
                    near(f[2], original.faces[g][(r + 2) % 3]))
                    found = matched[g] = true;
        EXPECT_TRUE(found) << "a decoded face that is not in the original";
    }
}

TriangleMesh decoded(const TriangleMesh& m, double quantum, std::size_t* bytes = nullptr) {
    ByteWriter w;
    encode_mesh(m, quantum, w);
    if (bytes) *bytes = w.bytes().size();
    ByteReader r(w.bytes(), "test");
    TriangleMesh d = decode_mesh(r, quantum);
    EXPECT_TRUE(r.at_end());
    return d;
}

// A closed latitude-longitude sphere: 2 poles and rings x segments vertices.
TriangleMesh sphere(int rings, int segments, float radius) {
    TriangleMesh m;
    m.vertices.emplace_back(0, 0, radius);
    for (int i = 1; i <= rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const float theta = 3.14159265f * i / (rings + 1), phi = 6.2831853f * j / segments;
            m.vertices.emplace_back(radius * std::sin(theta) * std::cos(phi), radius * std::sin(theta) * std::sin(phi),
                                    radius * std::cos(theta));
        }
    m.vertices.emplace_back(0, 0, -radius);
    const int south = static_cast<int>(m.vertices.size()) - 1;
    const auto at = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
    for (int j = 0; j < segments; ++j) {
        m.faces.push_back({0, at(1, j), at(1, j + 1)});
        m.faces.push_back({south, at(rings, j + 1), at(rings, j)});
        for (int i = 1; i < rings; ++i) {
            m.faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
    return m;
}

TEST(MeshCoder, RoundTripWithinHalfAQuantum) {
    const TriangleMesh m = octahedron({1.234f, -5.678f, 9.1f}, 0.37f);
    const TriangleMesh d = decoded(m, 0.005);
    ASSERT_EQ(d.vertices.size(), m.vertices.size());
    EXPECT_TRUE(check_closed(d).closed());
    expect_same_faces(d, m, 0.0025f);
}

// Faces are visited across shared edges, so a closed surface costs a few bits per face: the
// 960-face sphere takes 0.56 byte per face deflated, under 0.75 (version 3, a vertex index per corner and
// raw position deltas, took 1.54). Decoding and encoding again gives the same bytes, faces
// shuffled in the input give the same faces.
TEST(MeshCoder, AClosedSurfaceCostsLittleAndRoundTrips) {
    TriangleMesh m = sphere(16, 30, 1.5f);
    ASSERT_TRUE(check_closed(m).closed());
    std::size_t bytes = 0;
    const TriangleMesh d = decoded(m, 0.005, &bytes);
    EXPECT_TRUE(check_closed(d).closed());
    expect_same_faces(d, m, 0.0025f);
    ByteWriter once, twice;
    encode_mesh(m, 0.005, once);
    encode_mesh(d, 0.005, twice);
    EXPECT_EQ(once.bytes(), twice.bytes());
    uLongf deflated = compressBound(static_cast<uLong>(bytes));
    std::string packed(deflated, '\0');
    ASSERT_EQ(compress2(reinterpret_cast<Bytef*>(packed.data()), &deflated, reinterpret_cast<const Bytef*>(once.bytes().data()),
                        static_cast<uLong>(bytes), 9),
              Z_OK);
    EXPECT_LT(deflated, 3 * m.faces.size() / 4) << deflated << " deflated bytes for " << m.faces.size() << " faces";

    std::mt19937 rng(7);
    std::shuffle(m.faces.begin(), m.faces.end(), rng);
    expect_same_faces(decoded(m, 0.005), m, 0.0025f);
}

// Any mesh codes, not only closed ones: open borders, several parts, a face repeating a vertex,
// an edge with four faces, unused vertices (dropped).
TEST(MeshCoder, OpenNonManifoldAndSeveralPartsRoundTrip) {
    TriangleMesh m = sphere(4, 6, 1.0f);
    m.faces.erase(m.faces.begin() + 3);                      // a hole
    const TriangleMesh other = octahedron({5, 0, 0}, 0.5f);  // a second part
    const int base = static_cast<int>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), other.vertices.begin(), other.vertices.end());
    for (const auto& f : other.faces) m.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
    m.faces.push_back({base, base + 2, base + 4});  // a repeated face: its edges now have 3 and 4 faces
    m.faces.push_back({base, base, base + 1});      // degenerate
    m.vertices.emplace_back(9, 9, 9);               // unused
    const TriangleMesh d = decoded(m, 0.005);
    EXPECT_EQ(d.vertices.size(), m.vertices.size() - 1);
    expect_same_faces(d, m, 0.0025f);
}

// A closed double cone with 3000 faces around each apex round-trips: the border lookups drop the
// closed half-edges they pass (so that a damaged file's fans cannot make decoding quadratic) and
// must still find the open ones.
TEST(MeshCoder, HighDegreeVerticesRoundTrip) {
    TriangleMesh m;
    const int ring = 3000;
    m.vertices.emplace_back(0, 0, 1);
    m.vertices.emplace_back(0, 0, -1);
    for (int j = 0; j < ring; ++j) {
        const float phi = 6.2831853f * j / ring;
        m.vertices.emplace_back(std::cos(phi), std::sin(phi), 0);
    }
    for (int j = 0; j < ring; ++j) {
        const int a = 2 + j, b = 2 + (j + 1) % ring;
        m.faces.push_back({0, a, b});
        m.faces.push_back({1, b, a});
    }
    ASSERT_TRUE(check_closed(m).closed());
    const TriangleMesh d = decoded(m, 0.0001);
    EXPECT_TRUE(check_closed(d).closed());
    expect_same_faces(d, m, 0.00005f);
}

// Damaged mesh bytes are bad input, never a crash or a hang: every truncation and every
// single-byte change of a coded sphere either decodes or throws Error.
TEST(MeshCoder, DamagedBytesAreRefused) {
    ByteWriter w;
    encode_mesh(sphere(5, 8, 1.0f), 0.005, w);
    const std::string bytes = w.bytes();
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        ByteReader r(std::string_view(bytes).substr(0, n), "test");
        EXPECT_EQ(error_code_of([&] { decode_mesh(r, 0.005); }), ExitCode::InvalidInput) << "truncated at " << n;
    }
    for (std::size_t i = 0; i < bytes.size(); ++i)
        for (const unsigned char value : {0x00, 0x01, 0x03, 0x04, 0x05, 0x7f, 0xff}) {
            std::string damaged = bytes;
            damaged[i] = static_cast<char>(value);
            ByteReader r(damaged, "test");
            try {
                decode_mesh(r, 0.005);
            } catch (const Error& e) {
                EXPECT_EQ(e.code(), ExitCode::InvalidInput);
            }
        }
}

TEST(ByteCoder, VarintsAndZigzag) {
    ByteWriter w;
    for (std::int64_t v : {0LL, 1LL, -1LL, 63LL, -64LL, 1000000LL, -123456789LL}) w.svarint(v);
    w.varint(300);
    EXPECT_EQ(w.bytes().size(), 1u + 1 + 1 + 1 + 1 + 3 + 4 + 2);
    ByteReader r(w.bytes(), "test");
    for (std::int64_t v : {0LL, 1LL, -1LL, 63LL, -64LL, 1000000LL, -123456789LL}) EXPECT_EQ(r.svarint(), v);
    EXPECT_EQ(r.varint(), 300u);
    EXPECT_EQ(error_code_of([&] { r.u8(); }), ExitCode::InvalidInput);
}

TEST(Tlobe, RoundTripKeepsEverythingWithinTheQuanta) {
    const LobeTree t = sample_tree();
    const std::string bytes = encode_tlobe(t);
    const LobeTree d = decode_tlobe(bytes, "sample.tlobe");
    EXPECT_EQ(d.species, t.species);
    EXPECT_FLOAT_EQ(d.beta, 1.3f);
    EXPECT_FLOAT_EQ(d.fs, 0.85f);
    EXPECT_FLOAT_EQ(d.root_diameter, 0.3f);
    EXPECT_EQ(d.skeleton.origin, t.skeleton.origin);  // doubles, exactly
    ASSERT_EQ(d.skeleton.size(), t.skeleton.size());
    for (std::size_t i = 0; i < t.skeleton.size(); ++i) {
        EXPECT_EQ(d.skeleton.nodes[i].parent, t.skeleton.nodes[i].parent);
        EXPECT_EQ(d.skeleton.nodes[i].children, t.skeleton.nodes[i].children);
        EXPECT_LE((d.skeleton.nodes[i].position - t.skeleton.nodes[i].position).cwiseAbs().maxCoeff(), 0.0026f);
        EXPECT_NEAR(d.skeleton.nodes[i].radius, t.skeleton.nodes[i].radius, 0.00026f);
    }
    ASSERT_EQ(d.lobes.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(d.lobes[k].seed_node, t.lobes[k].seed_node);
        EXPECT_EQ(d.lobes[k].points, t.lobes[k].points);
        EXPECT_GT(d.lobes[k].seed_direction.dot(t.lobes[k].seed_direction), 0.999f);
        EXPECT_TRUE(check_closed(d.lobes[k].mesh).closed());
        EXPECT_NEAR(d.lobes[k].volume(), t.lobes[k].volume(), 0.02 * t.lobes[k].volume());
    }
    // Decoding then encoding again gives the same bytes (quantization is idempotent).
    EXPECT_TRUE(encode_tlobe(d) == bytes) << "re-encoding changed the bytes";
}

TEST(Tlobe, DetectsCorruptionTruncationAndForeignFiles) {
    const std::string bytes = encode_tlobe(sample_tree());
    std::string flipped = bytes;
    flipped[bytes.size() / 2] ^= 0x10;
    EXPECT_EQ(error_code_of([&] { decode_tlobe(flipped, "x"); }), ExitCode::InvalidInput);
    EXPECT_EQ(error_code_of([&] { decode_tlobe(bytes.substr(0, bytes.size() - 3), "x"); }), ExitCode::InvalidInput);
    EXPECT_EQ(error_code_of([&] { decode_tlobe("ply\nformat ascii 1.0\n", "x"); }), ExitCode::InvalidInput);
    // Other major versions (the old 2.x without leaf shares, a future one) are refused by name.
    for (const int major : {kTlobeOldestMajorVersion - 1, kTlobeMajorVersion + 1}) {
        std::string other = bytes;
        other[4] = static_cast<char>(major);
        const std::string version = "version " + std::to_string(major) + "." + std::to_string(kTlobeMinorVersion);
        try {
            decode_tlobe(other, "other.tlobe");
            ADD_FAILURE() << version << " accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput);
            EXPECT_NE(std::string(e.what()).find(version), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("treelobes lobes"), std::string::npos) << e.what();
        }
    }
}

std::string file_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

// Version 4.0 holds the tree's leaf area (since 3.1) and each lobe's leaf share (since 3.2):
// they round-trip, shares within half a step of 1/254 (0 and 1 exactly), unknown ones (-1) stay
// unknown. A later minor version's appended fields are skipped, while bytes a known version does
// not define are refused, and so is a leaf area that no tree has.
TEST(Tlobe, LeafAreaAndLobeLeafSharesRoundTrip) {
    LobeTree t = sample_tree();
    t.leaf_area_m2 = 117.5;
    t.lobes[0].leaf_share = 0.0f;
    t.lobes[1].leaf_share = 0.873f;
    const std::string bytes = encode_tlobe(t);
    EXPECT_EQ(bytes[4], kTlobeMajorVersion);
    EXPECT_EQ(bytes[5], kTlobeMinorVersion);
    LobeTree back = decode_tlobe(bytes, "t.tlobe");
    EXPECT_EQ(back.leaf_area_m2, 117.5);
    EXPECT_EQ(back.lobes[0].leaf_share, 0.0f);
    EXPECT_NEAR(back.lobes[1].leaf_share, 0.873f, 0.5f / 254);
    t.lobes[0].leaf_share = 1.0f;
    t.lobes[1].leaf_share = -1.0f;
    back = decode_tlobe(encode_tlobe(t), "t.tlobe");
    EXPECT_EQ(back.lobes[0].leaf_share, 1.0f);
    EXPECT_LT(back.lobes[1].leaf_share, 0.0f);

    const auto append = [](std::string& payload) { payload += "more"; };
    EXPECT_EQ(decode_tlobe(rewritten(bytes, kTlobeMinorVersion + 1, append), "newer.tlobe").leaf_area_m2, 117.5);
    EXPECT_EQ(error_code_of([&] { decode_tlobe(rewritten(bytes, kTlobeMinorVersion, append), "x"); }), ExitCode::InvalidInput);
    const std::size_t shares = t.lobes.size();
    const auto without_shares = [shares](std::string& payload) { payload.resize(payload.size() - shares); };
    EXPECT_EQ(error_code_of([&] { decode_tlobe(rewritten(bytes, kTlobeMinorVersion, without_shares), "x"); }), ExitCode::InvalidInput);
    for (const float bad : {-1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        const auto overwrite = [bad, shares](std::string& payload) { std::memcpy(payload.data() + payload.size() - shares - 4, &bad, 4); };
        EXPECT_EQ(error_code_of([&] { decode_tlobe(rewritten(bytes, kTlobeMinorVersion, overwrite), "x"); }), ExitCode::InvalidInput)
                << bad;
    }
}

// Version 3 files (vertex indices per corner) still read: a file the 3.0 writer wrote, without
// leaf area (0: unknown) and leaf shares (-1: unknown), and the same file made 3.1 and 3.2 by
// appending them; bytes 3.2 does not define are refused.
TEST(Tlobe, VersionThreeFilesStillRead) {
    const std::string v3_0 = file_bytes(test::source_dir() / "tests/data/tlobe/lagerstroemia_v3_0.tlobe");
    ASSERT_EQ(v3_0[4], 3);
    const LobeTree old = decode_tlobe(v3_0, "3.0.tlobe");
    EXPECT_EQ(old.leaf_area_m2, 0.0);
    ASSERT_FALSE(old.lobes.empty());
    for (const Lobe& lobe : old.lobes) {
        EXPECT_LT(lobe.leaf_share, 0.0f);
        EXPECT_TRUE(check_closed(lobe.mesh).closed());
    }
    const float area = 42.25f;
    const auto with_area = [&](std::string& payload) { payload.append(reinterpret_cast<const char*>(&area), 4); };
    EXPECT_EQ(decode_tlobe(rewritten(v3_0, 1, with_area), "3.1.tlobe").leaf_area_m2, 42.25);
    const auto with_shares = [&](std::string& payload) { with_area(payload), payload.append(old.lobes.size(), '\x7f'); };
    const LobeTree v3_2 = decode_tlobe(rewritten(v3_0, 2, with_shares), "3.2.tlobe");
    EXPECT_NEAR(v3_2.lobes.front().leaf_share, 127.0f / 254, 1e-6f);
    EXPECT_EQ(error_code_of([&] { decode_tlobe(rewritten(v3_0, 1, with_shares), "x"); }), ExitCode::InvalidInput);
    // Encoded again, it becomes a version 4 file with the same lobes.
    const LobeTree again = decode_tlobe(encode_tlobe(old), "4.tlobe");
    ASSERT_EQ(again.lobes.size(), old.lobes.size());
    for (std::size_t k = 0; k < old.lobes.size(); ++k) expect_same_faces(again.lobes[k].mesh, old.lobes[k].mesh, 0.0025f);
}

// Points of a lobe: a dense 0.3 m ball in one corner of the lobe and a thin vertical line.
std::vector<Eigen::Vector3f> corner_points(const Eigen::Vector3f& centre) {
    std::vector<Eigen::Vector3f> pts;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-0.3f, 0.3f);
    while (pts.size() < 3000) {
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const float z = u(rng), y = u(rng), x = u(rng);
        const Eigen::Vector3f d(x, y, z);
        if (d.norm() <= 0.3f) pts.push_back(centre + d);
    }
    for (int i = 0; i < 50; ++i) pts.push_back(centre + Eigen::Vector3f(0.5f, 0, -0.4f + 0.016f * i));
    return pts;
}

TEST(Occupancy, GridHoldsEveryPointAndOnlyTheirCells) {
    const auto pts = corner_points({0.7f, -0.2f, 2.4f});
    const Occupancy o = occupancy_of(pts, 0.05f);
    for (const auto& p : pts) EXPECT_TRUE(o.occupied(p));
    EXPECT_FALSE(o.occupied({0.7f, -0.2f, 2.75f}));  // inside the grid, above the ball
    EXPECT_FALSE(o.occupied({5, 5, 5}));             // outside the grid
    // The ball's 0.113 m^3 over 0.05 m cells (about 900 cells plus its rim) and the line's 17 cells.
    EXPECT_GT(o.occupied_count(), 900u);
    EXPECT_LT(o.occupied_count(), 1500u);
    ByteWriter w;
    encode_occupancy(o, 0.005, w);
    ByteReader r(w.bytes(), "test");
    EXPECT_EQ(decode_occupancy(r, 0.005), o);
    EXPECT_TRUE(r.at_end());
    // Truncated masks and a mask with a child outside the grid are invalid input.
    ByteReader short_reader(std::string_view(w.bytes()).substr(0, w.bytes().size() - 1), "test");
    EXPECT_EQ(error_code_of([&] { decode_occupancy(short_reader, 0.005); }), ExitCode::InvalidInput);
    // 3 x 1 x 1 cells padded to a cube of depth 2: three masks (root, then the two occupied
    // level-1 nodes), so the root mask is the 3rd to last byte;
    // its children with y = 1 (bit 2) lie outside the grid.
    const Occupancy three = occupancy_of(std::vector<Eigen::Vector3f>{{0, 0, 0}, {0.12f, 0, 0}}, 0.05f);
    ByteWriter pw;
    encode_occupancy(three, 0.005, pw);
    ByteReader good_reader(pw.bytes(), "test");
    EXPECT_EQ(decode_occupancy(good_reader, 0.005), three);
    std::string outside = pw.bytes();
    outside[outside.size() - 3] = static_cast<char>(outside[outside.size() - 3] | 0x04);
    ByteReader outside_reader(outside, "test");
    EXPECT_EQ(error_code_of([&] { decode_occupancy(outside_reader, 0.005); }), ExitCode::InvalidInput);
}

TEST(Tlobe, OccupancyRoundTripOnTheFinestGridThatFits) {
    LobeTree t = sample_tree();
    for (Lobe& lobe : t.lobes) lobe.cluster_points = corner_points(t.seed_position(lobe) + Eigen::Vector3f(0, 0, 0.5f));
    const std::string bytes = encode_tlobe(t);
    const LobeTree d = decode_tlobe(bytes, "occupied.tlobe");
    const float finest = static_cast<float>(0.03);
    for (std::size_t k = 0; k < t.lobes.size(); ++k) {
        ASSERT_FALSE(d.lobes[k].occupancy.empty());
        EXPECT_NEAR(d.lobes[k].occupancy.cell, finest, 1e-6f);  // two small lobes fit the budget at the finest grid
        EXPECT_EQ(d.lobes[k].occupancy, occupancy_of(t.lobes[k].cluster_points, d.lobes[k].occupancy.cell));
        EXPECT_TRUE(d.lobes[k].cluster_points.empty());  // the points themselves are not stored
    }
    EXPECT_TRUE(encode_tlobe(d) == bytes) << "re-encoding a decoded tree changed the bytes";
    // A smaller budget coarsens the grid; a budget below the file without occupancy drops it.
    TlobeOptions small;
    small.max_bytes = bytes.size() - 1;
    const std::string coarse = encode_tlobe(t, small);
    EXPECT_LE(coarse.size(), small.max_bytes);
    EXPECT_GT(decode_tlobe(coarse, "coarse.tlobe").lobes[0].occupancy.cell, finest);
    TlobeOptions tiny;
    tiny.max_bytes = 100;
    for (const Lobe& lobe : decode_tlobe(encode_tlobe(t, tiny), "tiny.tlobe").lobes) EXPECT_TRUE(lobe.occupancy.empty());
    // Corruption inside the occupancy bits is still caught by the CRC.
    std::string flipped = bytes;
    flipped[bytes.size() - 5] ^= 0x01;
    EXPECT_EQ(error_code_of([&] { decode_tlobe(flipped, "x"); }), ExitCode::InvalidInput);
}

// The sample tree with finely meshed 0.6 m balls for lobes, each holding a cluster of points.
LobeTree tree_with_ball_lobes() {
    LobeTree t = sample_tree();
    for (Lobe& lobe : t.lobes) {
        const Eigen::Vector3f centre = t.seed_position(lobe) + Eigen::Vector3f(0, 0, 0.5f);
        lobe.mesh = sphere(16, 30, 0.6f);
        for (auto& v : lobe.mesh.vertices) v += centre;
        lobe.cluster_points = corner_points(centre);
    }
    return t;
}

// When no occupancy grid fits the budget, the lobe surfaces are simplified (halving their faces)
// until one does: the file keeps the budget, its lobes stay closed with fewer faces, and they
// keep an occupancy. Without fractions to try, the file stays over the budget with full surfaces
// and no occupancy.
TEST(Tlobe, LobeSurfacesAreSimplifiedWhenNoGridFits) {
    const LobeTree t = tree_with_ball_lobes();
    const std::size_t full_faces = t.lobes[0].mesh.faces.size();
    const double full_volume = t.lobes[0].mesh.signed_volume();
    TlobeOptions unsimplified;
    unsimplified.lobe_face_fractions.clear();
    unsimplified.max_bytes = 100;
    const std::string bare = encode_tlobe(t, unsimplified);  // full surfaces, no occupancy
    for (const Lobe& lobe : decode_tlobe(bare, "bare.tlobe").lobes) {
        EXPECT_TRUE(lobe.occupancy.empty());
        EXPECT_EQ(lobe.mesh.faces.size(), full_faces);
    }
    TlobeOptions tight;
    tight.max_bytes = bare.size();
    const std::string file = encode_tlobe(t, tight);
    EXPECT_LE(file.size(), tight.max_bytes);
    for (const Lobe& lobe : decode_tlobe(file, "tight.tlobe").lobes) {
        EXPECT_FALSE(lobe.occupancy.empty());
        EXPECT_LT(lobe.mesh.faces.size(), full_faces);
        EXPECT_GE(lobe.mesh.faces.size(), tight.min_lobe_faces);
        EXPECT_TRUE(check_closed(lobe.mesh).closed());
        // Inflated back after the edge collapse: it still holds the whole 0.6 m ball.
        EXPECT_GE(lobe.mesh.signed_volume(), full_volume);
    }
    for (const double bad : {0.0, 1.0, -0.5}) {
        TlobeOptions o;
        o.lobe_face_fractions = {bad};
        EXPECT_EQ(error_code_of([&] { encode_tlobe(t, o); }), ExitCode::Usage) << bad;
    }
    TlobeOptions too_few;
    too_few.min_lobe_faces = 3;
    EXPECT_EQ(error_code_of([&] { encode_tlobe(t, too_few); }), ExitCode::Usage);
}

// A budget that the full surfaces meet only with a 0.6 m grid: the surfaces are simplified
// instead, to keep a 5 cm grid (the grids up to coarsest_cell_before_simplifying come first);
// with that bound below every grid, the coarse grid keeps the full surfaces.
TEST(Tlobe, SurfacesAreSimplifiedBeforeTheGridGrowsCoarse) {
    const LobeTree t = tree_with_ball_lobes();
    const std::size_t full_faces = t.lobes[0].mesh.faces.size();
    TlobeOptions full_and_coarse;
    full_and_coarse.occupancy_cells = {0.6};
    const std::string coarse_file = encode_tlobe(t, full_and_coarse);
    ASSERT_EQ(decode_tlobe(coarse_file, "coarse.tlobe").lobes[0].mesh.faces.size(), full_faces);

    TlobeOptions o;
    o.occupancy_cells = {0.05, 0.6};
    o.max_bytes = coarse_file.size();
    const LobeTree fine = decode_tlobe(encode_tlobe(t, o), "fine.tlobe");
    for (const Lobe& lobe : fine.lobes) {
        EXPECT_NEAR(lobe.occupancy.cell, 0.05f, 1e-6f);
        EXPECT_LT(lobe.mesh.faces.size(), full_faces);
    }
    o.coarsest_cell_before_simplifying = 0.01;
    EXPECT_EQ(encode_tlobe(t, o), coarse_file);
    o.coarsest_cell_before_simplifying = 0;
    EXPECT_EQ(error_code_of([&] { encode_tlobe(t, o); }), ExitCode::Usage);
}

TEST(Tlobe, FileRoundTripAndBadOptions) {
    test::TempDir dir;
    const LobeTree t = sample_tree();
    write_tlobe(t, dir / "t.tlobe");
    EXPECT_EQ(read_tlobe(dir / "t.tlobe").lobes.size(), 2u);
    EXPECT_EQ(error_code_of([&] { read_tlobe(dir / "missing.tlobe"); }), ExitCode::InvalidInput);
    TlobeOptions bad;
    bad.quantum = 0;
    EXPECT_EQ(error_code_of([&] { encode_tlobe(t, bad); }), ExitCode::Usage);
}

// Found by the tlobe_payload fuzzer (UBSan: signed overflow adding a huge coordinate delta to its
// parent's coordinate): a delta-coded coordinate outside the writer's int32 grid is bad input.
TEST(Tlobe, CoordinateDeltaBeyondTheGridIsBadInputNotAnOverflow) {
    std::ifstream in(test::source_dir() / "tests/data/fuzz/tlobe_payload_coordinate_overflow.bin", std::ios::binary);
    const std::string payload((std::istreambuf_iterator<char>(in)), {});
    ASSERT_FALSE(payload.empty());
    EXPECT_THROW(lobes::decode_tlobe_payload(payload, "fuzz input"), Error);

    ByteWriter out;
    out.svarint(std::numeric_limits<std::int32_t>::max());
    out.svarint(1);
    out.svarint(std::numeric_limits<std::int64_t>::min());
    ByteReader reader(out.bytes(), "test");
    EXPECT_EQ(reader.delta_coordinate(0), std::numeric_limits<std::int32_t>::max());
    EXPECT_THROW(reader.delta_coordinate(std::numeric_limits<std::int32_t>::max()), Error);  // one past the grid
    EXPECT_THROW(reader.delta_coordinate(0), Error);                                         // an absurd delta
}
