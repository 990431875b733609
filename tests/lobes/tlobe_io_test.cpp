#include "geometry/closed_mesh.hpp"
#include "geometry/polyline.hpp"
#include "lobes/mesh_coder.hpp"
#include "lobes/occupancy.hpp"
#include "lobes/tlobe_io.hpp"

#include "core/error.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
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
    // Encoded again, it becomes a file of the current version with the same lobes (vertices on the 2 cm grid).
    const LobeTree again = decode_tlobe(encode_tlobe(old), "5.tlobe");
    ASSERT_EQ(again.lobes.size(), old.lobes.size());
    for (std::size_t k = 0; k < old.lobes.size(); ++k) expect_same_faces(again.lobes[k].mesh, old.lobes[k].mesh, 0.01f);
}

constexpr std::size_t kAilanthusV4OccupiedCells = 1571;

// Version 4 files (occupancy as a byte of child bits per octree node, lobe vertices on the
// skeleton's 5 mm grid) still read: a file the 4.0 writer wrote (`treelobes lobes
// data/synthetic/ailanthus_altissima_5.las --species ailanthus_altissima --budget-kb 3`), whose
// five lobes hold occupancy on 3 cm cells; encoded again in the current version, the cells are the same.
TEST(Tlobe, VersionFourFilesStillRead) {
    const std::string v4 = file_bytes(test::source_dir() / "tests/data/tlobe/ailanthus_altissima_v4_0.tlobe");
    ASSERT_EQ(v4[4], 4);
    const LobeTree old = decode_tlobe(v4, "4.0.tlobe");
    ASSERT_EQ(old.lobes.size(), 5u);
    std::size_t occupied = 0;
    for (const Lobe& lobe : old.lobes) {
        EXPECT_NEAR(lobe.occupancy.cell, 0.03f, 1e-6f);
        EXPECT_TRUE(check_closed(lobe.mesh).closed());
        occupied += lobe.occupancy.occupied_count();
    }
    EXPECT_EQ(occupied, kAilanthusV4OccupiedCells);
    const std::string now = encode_tlobe(old);
    EXPECT_EQ(now[4], kTlobeMajorVersion);
    EXPECT_LT(now.size(), v4.size());
    const LobeTree again = decode_tlobe(now, "now.tlobe");
    for (std::size_t k = 0; k < old.lobes.size(); ++k) {
        EXPECT_EQ(again.lobes[k].occupancy, old.lobes[k].occupancy);
        expect_same_faces(again.lobes[k].mesh, old.lobes[k].mesh, 0.01f);
    }
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
    const Occupancy line = occupancy_of(std::vector<Eigen::Vector3f>{{0, 0, 0}, {0.12f, 0, 0}}, 0.05f);  // 3 x 1 x 1 cells
    const std::vector<const Occupancy*> grids{&o, &line};
    ByteWriter w;
    for (const Occupancy* grid : grids) encode_occupancy_grid(*grid, 0.005, w);
    const std::string cells = encode_occupancy_cells(grids);
    // The ball's ~1,100 cells, and the octree nodes above them, in far fewer bytes than a byte per node.
    EXPECT_LT(cells.size(), 250u);
    const auto decoded = [&](std::string_view stream) {
        ByteReader r(w.bytes(), "test");
        std::vector<Occupancy> back{decode_occupancy_grid(r, 0.005), decode_occupancy_grid(r, 0.005)};
        EXPECT_TRUE(r.at_end());
        decode_occupancy_cells(stream, back, "test");
        return back;
    };
    const std::vector<Occupancy> back = decoded(cells);
    EXPECT_EQ(back[0], o);
    EXPECT_EQ(back[1], line);
    // A truncated stream, one with a byte too many, and cells for grids that have none are invalid input.
    EXPECT_EQ(error_code_of([&] { decoded(std::string_view(cells).substr(0, cells.size() - 1)); }), ExitCode::InvalidInput);
    EXPECT_EQ(error_code_of([&] { decoded(cells + '\0'); }), ExitCode::InvalidInput);
    std::vector<Occupancy> none(1);
    EXPECT_EQ(error_code_of([&] { decode_occupancy_cells(cells, none, "test"); }), ExitCode::InvalidInput);
    EXPECT_TRUE(encode_occupancy_cells(std::vector<const Occupancy*>{&none[0]}).empty());
    // A grid without an occupied cell (only a damaged version 4 file holds one) is stored as none.
    Occupancy hollow = line;
    std::fill(hollow.bits.begin(), hollow.bits.end(), 0);
    ByteWriter hw;
    encode_occupancy_grid(hollow, 0.005, hw);
    ByteReader hr(hw.bytes(), "test");
    EXPECT_TRUE(decode_occupancy_grid(hr, 0.005).empty());
    EXPECT_TRUE(encode_occupancy_cells(std::vector<const Occupancy*>{&hollow}).empty());
    // Grids of more cells than a file may hold are refused before anything is allocated.
    std::vector<Occupancy> huge(5);
    for (Occupancy& g : huge) {
        g.cell = 0.05f;
        g.size = {256, 256, 256};
    }
    EXPECT_EQ(error_code_of([&] { decode_occupancy_cells(cells, huge, "test"); }), ExitCode::InvalidInput);
}

TEST(Tlobe, OccupancyRoundTripOnTheFinestGridThatFits) {
    LobeTree t = sample_tree();
    for (Lobe& lobe : t.lobes) lobe.cluster_points = corner_points(t.seed_position(lobe) + Eigen::Vector3f(0, 0, 0.5f));
    TlobeOptions every_grid;  // the grids finer than the points can draw are tested below
    every_grid.surfaces_from_occupancy = false;  // the stored surfaces' ladder (derived ones: further below)
    every_grid.min_points_per_cell = 0;
    const std::string bytes = encode_tlobe(t, every_grid);
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
    TlobeOptions small = every_grid;
    small.max_bytes = bytes.size() - 1;
    const std::string coarse = encode_tlobe(t, small);
    EXPECT_LE(coarse.size(), small.max_bytes);
    EXPECT_GT(decode_tlobe(coarse, "coarse.tlobe").lobes[0].occupancy.cell, finest);
    TlobeOptions tiny = every_grid;
    tiny.max_bytes = 100;
    for (const Lobe& lobe : decode_tlobe(encode_tlobe(t, tiny), "tiny.tlobe").lobes) EXPECT_TRUE(lobe.occupancy.empty());
    // Corruption inside the occupancy bits is still caught by the CRC.
    std::string flipped = bytes;
    flipped[bytes.size() - 5] ^= 0x01;
    EXPECT_EQ(error_code_of([&] { decode_tlobe(flipped, "x"); }), ExitCode::InvalidInput);
}

// A grid finer than the points can draw is skipped: the finest grid used holds at least
// min_points_per_cell points per occupied cell (the ball's 3,050 points: about 2.7 per cell at
// 3 cm), whatever the budget; when no grid does, the coarsest one is used.
TEST(Tlobe, OccupancyGridNoFinerThanThePointsDraw) {
    LobeTree t = sample_tree();
    for (Lobe& lobe : t.lobes) lobe.cluster_points = corner_points(t.seed_position(lobe) + Eigen::Vector3f(0, 0, 0.5f));
    const TlobeOptions o;
    ASSERT_EQ(o.min_points_per_cell, 6.0);
    const auto points_per_cell = [&](double cell) {
        std::size_t points = 0, cells = 0;
        for (const Lobe& lobe : t.lobes) {
            points += lobe.cluster_points.size();
            cells += occupancy_of(lobe.cluster_points, static_cast<float>(cell)).occupied_count();
        }
        return static_cast<double>(points) / static_cast<double>(cells);
    };
    ASSERT_LT(points_per_cell(o.occupancy_cells.front()), o.min_points_per_cell);
    const auto drawable = std::find_if(o.occupancy_cells.begin(), o.occupancy_cells.end(),
                                       [&](double cell) { return points_per_cell(cell) >= o.min_points_per_cell; });
    ASSERT_NE(drawable, o.occupancy_cells.end());
    EXPECT_NEAR(decode_tlobe(encode_tlobe(t, o), "drawn.tlobe").lobes[0].occupancy.cell, static_cast<float>(*drawable), 1e-6f);
    TlobeOptions never = o;
    never.min_points_per_cell = 1e6;
    EXPECT_NEAR(decode_tlobe(encode_tlobe(t, never), "coarsest.tlobe").lobes[0].occupancy.cell,
                static_cast<float>(o.occupancy_cells.back()), 1e-6f);
}

// The sample tree with finely meshed 0.6 m balls for lobes, each holding a cluster of points.
// Their radii vary by up to 10 % from vertex to vertex, as an alpha shape's do: a regular sphere
// is predicted so well by the mesh coder that simplifying it would not make its coding smaller.
LobeTree tree_with_ball_lobes() {
    LobeTree t = sample_tree();
    for (Lobe& lobe : t.lobes) {
        const Eigen::Vector3f centre = t.seed_position(lobe) + Eigen::Vector3f(0, 0, 0.5f);
        lobe.mesh = sphere(16, 30, 0.6f);
        for (std::size_t i = 0; i < lobe.mesh.vertices.size(); ++i) lobe.mesh.vertices[i] *= 1.0f + 0.1f * std::sin(7.3f * static_cast<float>(i));
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

// A budget that the full surfaces meet only with a 0.6 m grid, not a 5 cm one: the surfaces are
// simplified instead, to keep the 5 cm grid (a finer grid is worth more than fuller surfaces);
// without simplifications at each grid, the coarse grid keeps the full surfaces.
TEST(Tlobe, SurfacesAreSimplifiedBeforeTheGridGrowsCoarse) {
    const LobeTree t = tree_with_ball_lobes();
    const std::size_t full_faces = t.lobes[0].mesh.faces.size();
    TlobeOptions full_and_coarse;
    full_and_coarse.surfaces_from_occupancy = false;  // the stored surfaces' ladder
    full_and_coarse.min_points_per_cell = 0;  // the ball's 3,050 points are too few for 5 cm cells
    full_and_coarse.occupancy_cells = {0.6};
    const std::string coarse_file = encode_tlobe(t, full_and_coarse);
    ASSERT_EQ(decode_tlobe(coarse_file, "coarse.tlobe").lobes[0].mesh.faces.size(), full_faces);
    TlobeOptions full_and_fine = full_and_coarse;
    full_and_fine.occupancy_cells = {0.05};
    const std::size_t fine_full = encode_tlobe(t, full_and_fine).size();
    ASSERT_LT(coarse_file.size(), fine_full);

    TlobeOptions o = full_and_coarse;
    o.occupancy_cells = {0.05, 0.6};
    o.max_bytes = fine_full - 1;
    const LobeTree fine = decode_tlobe(encode_tlobe(t, o), "fine.tlobe");
    for (const Lobe& lobe : fine.lobes) {
        EXPECT_NEAR(lobe.occupancy.cell, 0.05f, 1e-6f);
        EXPECT_LT(lobe.mesh.faces.size(), full_faces);
    }
    o.simplifications_per_grid = 0;
    EXPECT_EQ(encode_tlobe(t, o), coarse_file);
}

// The main skeleton's bare twigs (a fork to a tip that seeds no lobe: a cluster too small for a
// lobe) go before the grid grows coarse: with a budget one byte below the whole tree's file on
// the fine grid, the file keeps that grid without the three short twigs and keeps the long one;
// with bare_twig_length 0 it falls to the coarse grid with every twig, and within the default
// budget every twig is kept on the fine grid.
TEST(Tlobe, BareTwigsAreLeftOutBeforeTheGridGrowsCoarse) {
    LobeTree t = tree_with_ball_lobes();
    const auto add_twig = [&](const Eigen::Vector3f& direction, float length) {
        int node = 1;  // the fork below both lobes
        for (int k = 1; k <= 3; ++k)
            node = t.skeleton.add_node(t.skeleton.nodes[1].position + direction.normalized() * (length * static_cast<float>(k) / 3), 0.01f,
                                       node);
        return node;
    };
    for (const Eigen::Vector3f& direction : {Eigen::Vector3f(1, 0, 0.2f), Eigen::Vector3f(0, 1, 0.3f), Eigen::Vector3f(-1, -1, 0.1f)})
        add_twig(direction, 0.4f);
    const int long_tip = add_twig(Eigen::Vector3f(0, -1, 0.5f), 1.5f);
    const Eigen::Vector3f long_tip_position = t.skeleton.nodes[long_tip].position;
    ASSERT_EQ(t.skeleton.tip_count(), 6u);

    TlobeOptions o;
    o.surfaces_from_occupancy = false;  // the stored surfaces' ladder
    o.min_points_per_cell = 0;  // the ball's 3,050 points are too few for 5 cm cells
    o.lobe_face_fractions.clear();
    o.occupancy_cells = {0.05};
    const std::size_t whole_on_fine = encode_tlobe(t, o).size();
    o.occupancy_cells = {0.05, 0.6};
    EXPECT_EQ(decode_tlobe(encode_tlobe(t, o), "roomy.tlobe").skeleton.tip_count(), 6u);

    o.max_bytes = whole_on_fine - 1;
    const LobeTree without = decode_tlobe(encode_tlobe(t, o), "without.tlobe");
    EXPECT_NEAR(without.lobes[0].occupancy.cell, 0.05f, 1e-6f);
    EXPECT_EQ(without.skeleton.tip_count(), 3u);  // the two lobe seeds and the long twig
    bool long_twig_kept = false;
    for (const auto& node : without.skeleton.nodes) long_twig_kept = long_twig_kept || (node.position - long_tip_position).norm() < 0.005f;
    EXPECT_TRUE(long_twig_kept);
    for (const Lobe& lobe : without.lobes) EXPECT_TRUE(without.skeleton.nodes[lobe.seed_node].children.empty());

    o.bare_twig_length = 0;
    const LobeTree coarse = decode_tlobe(encode_tlobe(t, o), "coarse.tlobe");
    EXPECT_NEAR(coarse.lobes[0].occupancy.cell, 0.6f, 1e-6f);
    EXPECT_EQ(coarse.skeleton.tip_count(), 6u);
    o.bare_twig_length = -1;
    EXPECT_EQ(error_code_of([&] { encode_tlobe(t, o); }), ExitCode::Usage);
}

// A lobe's surface derived from its occupancy (.tlobe 6.0): closed, around every occupied cell,
// the same on every call; an occupancy too large or empty, or a bad alpha factor, is bad input.
TEST(Occupancy, SurfaceDerivedAroundEveryOccupiedCell) {
    std::vector<Eigen::Vector3f> points;
    for (int i = 0; i < 6; ++i) points.emplace_back(0.05f + 0.1f * static_cast<float>(i), 0.05f, 0.05f);  // an L of cells
    for (int k = 1; k < 4; ++k) points.emplace_back(0.05f, 0.05f, 0.05f + 0.1f * static_cast<float>(k));
    const Occupancy occupancy = occupancy_of(points, 0.1f);
    ASSERT_EQ(occupancy.occupied_count(), 9u);
    const TriangleMesh surface = surface_of_occupancy(occupancy, 5.0, "l.tlobe");
    EXPECT_TRUE(check_closed(surface).closed());
    EXPECT_GT(surface.signed_volume(), 0.0);
    Eigen::Vector3f low = surface.vertices.front(), high = low;
    for (const Eigen::Vector3f& v : surface.vertices) {
        low = low.cwiseMin(v);
        high = high.cwiseMax(v);
    }
    for (std::size_t i = 0; i < occupancy.bits.size(); ++i)
        if (occupancy.bits[i]) {
            const Eigen::Vector3f c = occupancy.cell_centre(i);
            EXPECT_TRUE((c.array() > low.array()).all() && (c.array() < high.array()).all()) << c.transpose();
        }
    EXPECT_NEAR(high.x() - low.x(), 0.6f, 1e-5f);
    EXPECT_NEAR(high.z() - low.z(), 0.4f, 1e-5f);
    const TriangleMesh again = surface_of_occupancy(occupancy, 5.0, "l.tlobe");
    EXPECT_EQ(again.vertices, surface.vertices);
    EXPECT_EQ(again.faces, surface.faces);

    EXPECT_EQ(error_code_of([&] { surface_of_occupancy(Occupancy{}, 5.0, "x"); }), ExitCode::InvalidInput);
    EXPECT_EQ(error_code_of([&] { surface_of_occupancy(occupancy, std::nan(""), "x"); }), ExitCode::InvalidInput);
    Occupancy full;
    full.cell = 0.1f;
    full.size = {32, 32, 9};
    full.bits.assign(32 * 32 * 9, 1);  // 9,216 cells: more than a lobe may derive from
    EXPECT_EQ(error_code_of([&] { surface_of_occupancy(full, 5.0, "x"); }), ExitCode::InvalidInput);
}

// Where the stored surfaces leave no room even for the finest grid, the file stores none and the
// reader derives them from the occupancy (version 6.0): the file keeps the fine grid, its lobes
// are closed around their cells, re-encoding gives the same bytes; within a roomy budget the
// surfaces are stored. A lobe with neither surface nor occupancy is bad input, and in a 5.0
// file a lobe without faces stays without (5.0 writers never made one).
TEST(Tlobe, SurfacesComeFromTheOccupancyWhereNothingElseFits) {
    const LobeTree t = tree_with_ball_lobes();
    TlobeOptions o;
    o.min_points_per_cell = 0;  // the ball's 3,050 points are too few for 5 cm cells
    o.lobe_face_fractions.clear();
    o.occupancy_cells = {0.05};
    const std::string stored_on_fine = encode_tlobe(t, o);
    const LobeTree roomy = decode_tlobe(stored_on_fine, "roomy.tlobe");
    EXPECT_EQ(stored_on_fine[4], 6);
    for (std::size_t k = 0; k < t.lobes.size(); ++k) {
        EXPECT_FALSE(roomy.lobes[k].surface_from_occupancy);
        EXPECT_EQ(roomy.lobes[k].mesh.faces.size(), t.lobes[k].mesh.faces.size());
    }

    o.occupancy_cells = {0.05, 0.6};
    o.max_bytes = stored_on_fine.size() - 1;
    const std::string bytes = encode_tlobe(t, o);
    EXPECT_LE(bytes.size(), o.max_bytes);
    const LobeTree derived = decode_tlobe(bytes, "derived.tlobe");
    for (const Lobe& lobe : derived.lobes) {
        EXPECT_TRUE(lobe.surface_from_occupancy);
        EXPECT_NEAR(lobe.occupancy.cell, 0.05f, 1e-6f);
        EXPECT_TRUE(check_closed(lobe.mesh).closed());
        EXPECT_GT(lobe.mesh.signed_volume(), 0.9 * 0.05 * 0.05 * 0.05 * static_cast<double>(lobe.occupancy.occupied_count()));
    }
    EXPECT_TRUE(encode_tlobe(derived) == bytes) << "re-encoding a tree with derived surfaces changed the bytes";

    LobeTree hollow = sample_tree();  // no occupancy: nothing to derive a surface from
    hollow.lobes[0].mesh = TriangleMesh{};
    const std::string no_surface = encode_tlobe(hollow);
    EXPECT_EQ(error_code_of([&] { decode_tlobe(no_surface, "hollow.tlobe"); }), ExitCode::InvalidInput);
    std::string five = no_surface;
    five[4] = 5;
    EXPECT_TRUE(decode_tlobe(rewritten(five, 0, [](std::string&) {}), "five.tlobe").lobes[0].mesh.faces.empty());
}

// Terminalia's file of the rebuild bench (sample 13) written with every surface it could derive
// derived: its first lobe's 7,928 cells of 14 cm give no closed alpha shape, so the writer kept
// that lobe's surface. Writing the same lobes from points at the same grid under a tight budget
// keeps it again, and the file reads; a file that claimed that lobe's surface from its cells
// would be bad input.
TEST(Tlobe, SurfacesTheCellsCannotGiveAreKept) {
    const LobeTree file = decode_tlobe(file_bytes(test::source_dir() / "tests/data/tlobe/terminalia_v6_0.tlobe"), "terminalia.tlobe");
    ASSERT_FALSE(file.lobes[0].surface_from_occupancy);
    EXPECT_EQ(error_code_of([&] { surface_of_occupancy(file.lobes[0].occupancy, file.alpha_factor, "x"); }), ExitCode::InvalidInput);

    LobeTree from_points = file;  // the underivable lobe and the first two that derive
    from_points.lobes = {file.lobes[0]};
    for (const Lobe& lobe : file.lobes)
        if (lobe.surface_from_occupancy && from_points.lobes.size() < 3) from_points.lobes.push_back(lobe);
    ASSERT_EQ(from_points.lobes.size(), 3u);
    for (Lobe& lobe : from_points.lobes) {
        lobe.surface_from_occupancy = false;
        for (std::size_t i = 0; i < lobe.occupancy.bits.size(); ++i)
            if (lobe.occupancy.bits[i]) lobe.cluster_points.push_back(lobe.occupancy.cell_centre(i));
        lobe.occupancy = Occupancy{};
    }
    TlobeOptions o;
    o.min_points_per_cell = 0;
    o.lobe_face_fractions.clear();
    o.occupancy_cells = {file.lobes[0].occupancy.cell};
    o.skeleton_tolerance = 0;
    o.bare_twig_length = 0;  // the seeds of the lobes left out would be bare twigs
    o.max_bytes = 1000000;
    const std::size_t stored = encode_tlobe(from_points, o).size();
    o.max_bytes = stored - 1;
    const std::string bytes = encode_tlobe(from_points, o);
    const LobeTree written = decode_tlobe(bytes, "written.tlobe");
    EXPECT_FALSE(written.lobes[0].surface_from_occupancy);
    EXPECT_EQ(written.lobes[0].occupancy, file.lobes[0].occupancy);
    EXPECT_TRUE(written.lobes[1].surface_from_occupancy);
    EXPECT_TRUE(written.lobes[2].surface_from_occupancy);

    LobeTree claimed = file;
    claimed.lobes[0].surface_from_occupancy = true;
    EXPECT_EQ(error_code_of([&] { decode_tlobe(encode_tlobe(claimed), "claimed.tlobe"); }), ExitCode::InvalidInput);
}

// A reader derives surfaces from at most kMaxDerivedSurfaceCellsPerTree cells per file, so a
// damaged or hostile file cannot make it build alpha shapes without end: three lobes of 6,000
// cells each, every one within the per-lobe bound, are bad input together; two of them read.
TEST(Tlobe, AFileDerivesSurfacesFromABoundedNumberOfCells) {
    Lobe block = sample_tree().lobes[0];
    block.mesh = TriangleMesh{};
    block.surface_from_occupancy = true;
    const double quantum = static_cast<float>(TlobeOptions{}.quantum);                                      // as the file stores it
    block.occupancy.cell = static_cast<float>(static_cast<double>(std::llround(0.1 / quantum)) * quantum);  // 10 cm, on the quantum
    block.occupancy.size = {20, 20, 15};
    block.occupancy.bits.assign(20 * 20 * 15, 1);
    ASSERT_LE(block.occupancy.occupied_count(), kMaxDerivedSurfaceCells);
    LobeTree two = sample_tree();
    two.lobes = {block, block};
    const LobeTree read = decode_tlobe(encode_tlobe(two), "two.tlobe");
    ASSERT_EQ(read.lobes.size(), 2u);
    for (const Lobe& lobe : read.lobes) EXPECT_TRUE(check_closed(lobe.mesh).closed());
    LobeTree three = two;
    three.lobes.push_back(block);
    ASSERT_GT(3 * block.occupancy.occupied_count(), kMaxDerivedSurfaceCellsPerTree);
    EXPECT_EQ(error_code_of([&] { decode_tlobe(encode_tlobe(three), "three.tlobe"); }), ExitCode::InvalidInput);
}

// The simplifications beyond simplifications_per_grid come only when no grid fits with fewer:
// a budget that a 2 cm grid meets only with the surfaces at 1/16 keeps the 0.6 m grid when the
// surfaces may be simplified to 1/8 at each grid (the default), the 2 cm one when to 1/16.
TEST(Tlobe, DeepSimplificationsWaitForEveryGrid) {
    const LobeTree t = tree_with_ball_lobes();
    // Bytes of the file on the grid `cell` with the surfaces at `fraction` of their faces: the
    // budget one byte below the full surfaces' file on that grid makes the encoder simplify them.
    const auto size_with = [&](double cell, double fraction) {
        TlobeOptions o;
        o.surfaces_from_occupancy = false;  // the stored surfaces' ladder
        o.min_points_per_cell = 0;  // the ball's 3,050 points are too few for 2 cm cells
        o.occupancy_cells = {cell};
        o.lobe_face_fractions.clear();
        o.max_bytes = encode_tlobe(t, o).size() - 1;
        o.lobe_face_fractions = {fraction};
        const std::string file = encode_tlobe(t, o);
        EXPECT_NEAR(decode_tlobe(file, "sized.tlobe").lobes[0].occupancy.cell, static_cast<float>(cell), 1e-6f);
        return file.size();
    };
    const std::size_t fine_sixteenth = size_with(0.02, 0.0625);
    ASSERT_GT(size_with(0.02, 0.125), fine_sixteenth);
    ASSERT_LE(size_with(0.6, 0.125), fine_sixteenth);

    TlobeOptions budget;
    budget.surfaces_from_occupancy = false;
    budget.min_points_per_cell = 0;
    budget.occupancy_cells = {0.02, 0.6};
    budget.max_bytes = fine_sixteenth;
    ASSERT_EQ(budget.simplifications_per_grid, 3u);
    EXPECT_NEAR(decode_tlobe(encode_tlobe(t, budget), "three.tlobe").lobes[0].occupancy.cell, 0.6f, 1e-6f);
    budget.simplifications_per_grid = 4;
    const LobeTree fine = decode_tlobe(encode_tlobe(t, budget), "four.tlobe");
    EXPECT_NEAR(fine.lobes[0].occupancy.cell, 0.02f, 1e-6f);
    EXPECT_EQ(fine.lobes[0].mesh.faces.size(), size_t{60});  // 1/16 of the ball's 960
    // More simplifications per grid than fractions: each grid tries them all, full surfaces first.
    budget.simplifications_per_grid = 10;
    budget.max_bytes = 1000000;
    EXPECT_EQ(decode_tlobe(encode_tlobe(t, budget), "ten.tlobe").lobes[0].mesh.faces.size(), t.lobes[0].mesh.faces.size());
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
    TlobeOptions bad_lobe_grid;
    bad_lobe_grid.lobe_quantum = -0.02;
    EXPECT_EQ(error_code_of([&] { encode_tlobe(t, bad_lobe_grid); }), ExitCode::Usage);
}

// Lobe vertices lie on their own grid (lobe_quantum, stored in the file), the skeleton keeps the
// finer one.
TEST(Tlobe, LobeVerticesOnTheirOwnGrid) {
    const LobeTree t = sample_tree();
    TlobeOptions o;
    o.lobe_quantum = 0.05;
    const LobeTree d = decode_tlobe(encode_tlobe(t, o), "coarse_lobes.tlobe");
    for (std::size_t k = 0; k < t.lobes.size(); ++k) {
        expect_same_faces(d.lobes[k].mesh, t.lobes[k].mesh, 0.025f);
        for (const auto& v : d.lobes[k].mesh.vertices)
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c] / 0.05f, std::round(v[c] / 0.05f), 1e-3f);
    }
    for (std::size_t i = 0; i < t.skeleton.size(); ++i)
        EXPECT_LE((d.skeleton.nodes[i].position - t.skeleton.nodes[i].position).cwiseAbs().maxCoeff(), 0.0025f + 1e-5f);
}

// A trunk of 31 evenly spaced nodes, straight and evenly tapering but for a diameter bump at
// 1.5 m and a bend at 2 m, with a fork at 1 m to a thin straight lateral of 5 nodes and a lobe
// seeded at 0.5 m: the file keeps the root, the lobe's seed, the fork, the bump, the bend, both
// tips and the lateral's first node (its diameter is not the fork's), and drops the rest.
LobeTree tree_with_straight_chains() {
    LobeTree t = sample_tree();
    t.skeleton = TreeGraph{};
    t.skeleton.add_node({0, 0, 0}, 0.2f, -1);
    for (int i = 1; i <= 30; ++i) {
        const Eigen::Vector3f at = i <= 20 ? Eigen::Vector3f(0, 0, 0.1f * i) : Eigen::Vector3f(0.05f * (i - 20), 0, 2 + 0.1f * (i - 20));
        t.skeleton.add_node(at, 0.2f - 0.005f * i + (i == 15 ? 0.003f : 0.0f), i - 1);
    }
    for (int k = 1; k <= 5; ++k) t.skeleton.add_node({0.1f * k, 0, 1.0f}, 0.03f, k == 1 ? 10 : 30 + k - 1);
    t.lobes.resize(1);
    t.lobes[0].seed_node = 5;
    return t;
}

TEST(Tlobe, StraightSkeletonStretchesAreStoredByTheirEnds) {
    const LobeTree t = tree_with_straight_chains();
    const std::string bytes = encode_tlobe(t);
    const LobeTree d = decode_tlobe(bytes, "thinned.tlobe");
    // In pre-order, the trunk before the lateral; the bump keeps its neighbours too, as the taper
    // from the fork or the bend to it would miss their diameters by 4.8 mm.
    const std::vector<int> kept{0, 5, 10, 14, 15, 16, 20, 30, 31, 35};
    ASSERT_EQ(d.skeleton.size(), kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) {
        EXPECT_LE((d.skeleton.nodes[i].position - t.skeleton.nodes[kept[i]].position).cwiseAbs().maxCoeff(), 0.0026f) << "node " << i;
        EXPECT_NEAR(d.skeleton.nodes[i].radius, t.skeleton.nodes[kept[i]].radius, 0.00026f) << "node " << i;
    }
    EXPECT_EQ(d.lobes[0].seed_node, 1);
    EXPECT_TRUE(encode_tlobe(d) == bytes) << "thinning the decoded tree again changed the bytes";
    TlobeOptions every_node;
    every_node.skeleton_tolerance = 0;
    EXPECT_EQ(decode_tlobe(encode_tlobe(t, every_node), "all.tlobe").skeleton.size(), t.skeleton.size());
    TlobeOptions bad;
    bad.skeleton_tolerance = -0.01;
    EXPECT_EQ(error_code_of([&] { encode_tlobe(t, bad); }), ExitCode::Usage);
}

// A branch that wanders by up to 2 cm about its line: the default tolerance (3 cm) stores it by
// fewer nodes than 1 cm does, and every node left out lies within the tolerance (plus the
// 5 mm grid's rounding) of the branch the file stores.
TEST(Tlobe, SkeletonNodesWithinThreeCentimetresOfTheStoredBranchAreLeftOut) {
    LobeTree t = sample_tree();
    t.skeleton = TreeGraph{};
    constexpr int kNodes = 61;
    for (int i = 0; i < kNodes; ++i) {
        const float z = 0.05f * static_cast<float>(i);
        t.skeleton.add_node({0.02f * std::sin(z * 2.5f), 0.01f * std::cos(z * 4.0f), z}, 0.1f, i - 1);
    }
    t.lobes.resize(1);
    t.lobes[0].seed_node = kNodes - 1;
    const LobeTree stored = decode_tlobe(encode_tlobe(t), "wandering.tlobe");
    TlobeOptions one_centimetre;
    one_centimetre.skeleton_tolerance = 0.01;
    const std::size_t kept_at_1cm = decode_tlobe(encode_tlobe(t, one_centimetre), "1cm.tlobe").skeleton.size();
    EXPECT_LT(stored.skeleton.size(), kept_at_1cm);
    EXPECT_LT(kept_at_1cm, t.skeleton.size());
    for (const auto& node : t.skeleton.nodes) {
        float nearest = std::numeric_limits<float>::max();
        for (std::size_t k = 1; k < stored.skeleton.size(); ++k)
            nearest = std::min(
                    nearest, distance_to_segment(node.position, stored.skeleton.nodes[k - 1].position, stored.skeleton.nodes[k].position));
        EXPECT_LE(nearest, 0.03f + 0.0045f) << "node at z = " << node.position.z();
    }
}

// On an occupancy grid coarser than 8 x lobe_quantum, lobe vertices lie on an eighth of its cell.
TEST(Tlobe, LobeVerticesOnAnEighthOfACoarseCell) {
    LobeTree t = sample_tree();
    for (Lobe& lobe : t.lobes)
        for (Eigen::Vector3f& v : lobe.mesh.vertices) {
            v += Eigen::Vector3f(0.013f, 0.007f, 0.011f);  // off the 5 cm grid
            lobe.cluster_points.push_back(v);
        }
    TlobeOptions o;
    o.occupancy_cells = {0.4};
    const LobeTree d = decode_tlobe(encode_tlobe(t, o), "coarse_cells.tlobe");
    ASSERT_FLOAT_EQ(d.lobes[0].occupancy.cell, 0.4f);
    for (std::size_t k = 0; k < t.lobes.size(); ++k) {
        expect_same_faces(d.lobes[k].mesh, t.lobes[k].mesh, 0.025f + 1e-4f);
        for (const auto& v : d.lobes[k].mesh.vertices)
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c] / 0.05f, std::round(v[c] / 0.05f), 1e-3f);
    }
    EXPECT_TRUE(encode_tlobe(d, o) == encode_tlobe(t, o)) << "a decoded tree is not encoded on the grid it came on";
    o.lobe_quantum_per_cell = 0;
    const LobeTree fine = decode_tlobe(encode_tlobe(t, o), "fine.tlobe");
    bool off_the_coarse_grid = false;
    for (const auto& v : fine.lobes[0].mesh.vertices)
        for (int c = 0; c < 3; ++c) off_the_coarse_grid = off_the_coarse_grid || std::abs(v[c] / 0.05f - std::round(v[c] / 0.05f)) > 1e-3f;
    EXPECT_TRUE(off_the_coarse_grid);
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
