// The .dbf6 and .forest files: exact round trips of every LOD with both coders, world
// placement, random access to one tree, and clean errors for truncated or corrupted files.
#include "core/error.hpp"
#include "encode/forest_file.hpp"
#include "encode/lod.hpp"
#include "encode/tree_file.hpp"
#include "random_tree.hpp"
#include "support/test_support.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

TreeGraph sample_tree(std::uint32_t seed, int nodes = 400) {
    test::RandomTreeProfile profile;
    profile.max_nodes = nodes;
    profile.max_laterals = 2;
    profile.wiggle_degrees = 10;
    profile.fork_probability = 0.35;
    return test::random_tree(profile, seed);
}

TreeFileOptions file_options(Coder coder, int lods) {
    TreeFileOptions options;
    options.encode.internode_length = 0.1;
    options.lods = lods;
    options.coder = coder;
    return options;
}

// Every way of damaging a file must end in Error(InvalidInput), never in a crash or a hang.
template <class Read>
void expect_damage_rejected(const std::vector<std::uint8_t>& bytes, Read read) {
    for (std::size_t cut = 0; cut < bytes.size(); cut += 1 + bytes.size() / 97) {
        try {
            read(std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(cut)));
            ADD_FAILURE() << "truncated to " << cut << " of " << bytes.size() << " bytes: accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput) << e.what();
        }
    }
    std::mt19937 rng(17);
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<std::uint8_t> damaged = bytes;
        damaged[rng() % damaged.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
        try {
            read(damaged);
            ADD_FAILURE() << "bit flip accepted (trial " << trial << ")";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::InvalidInput) << e.what();
        }
    }
}

}  // namespace

TEST(TreeFile, EveryLodRoundTripsWithBothCoders) {
    const TreeGraph tree = sample_tree(3);
    for (Coder coder : {Coder::Interpolative, Coder::Best}) {
        const StoredTree stored = store_tree(tree, file_options(coder, 4));
        ASSERT_EQ(stored.lods.size(), 4u);
        ASSERT_EQ(stored.thresholds.size(), 3u);
        std::vector<StreamSizes> sizes;
        const std::vector<std::uint8_t> bytes = write_tree_file_bytes(stored, &sizes);
        ASSERT_EQ(sizes.size(), 4u);
        std::size_t streams = 0;
        for (const StreamSizes& s : sizes) streams += s.symbols + s.radii;
        EXPECT_LT(streams, bytes.size());
        EXPECT_LT(bytes.size(), streams + 80);  // header, thresholds, sizes and CRC are small
        const StoredTree all = read_tree_file_bytes(bytes, -1, "test");
        EXPECT_EQ(all.coder, coder);
        EXPECT_EQ(all.thresholds, stored.thresholds);
        EXPECT_EQ(all.resolution, stored.resolution);
        EXPECT_EQ(all.internode_length, stored.internode_length);
        EXPECT_EQ(all.root_radius, stored.root_radius);
        for (int k = 0; k < 4; ++k) {
            EXPECT_EQ(all.lods[k].symbols, stored.lods[k].symbols) << "LOD " << k;
            EXPECT_EQ(all.lods[k].radii, stored.lods[k].radii) << "LOD " << k;
            const StoredTree one = read_tree_file_bytes(bytes, k, "test");  // only LOD k decoded
            EXPECT_EQ(one.lods[k].symbols, stored.lods[k].symbols);
            if (k > 0) {
                EXPECT_TRUE(one.lods[0].symbols.empty());
            }
        }
        EXPECT_LT(stored.lods[3].radii.size(), stored.lods[0].radii.size());
        // The same input gives the same bytes.
        EXPECT_EQ(write_tree_file_bytes(store_tree(tree, file_options(coder, 4))), bytes);
        try {
            read_tree_file_bytes(bytes, 4, "test");
            FAIL() << "LOD 4 of 4 accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ExitCode::Usage);
        }
    }
}

TEST(TreeFile, DecodedSkeletonKeepsWorldCoordinates) {
    TreeGraph tree = sample_tree(4, 200);
    tree.origin = {512345.25, 5401234.5, 312.0};  // UTM-like
    const StoredTree stored = store_tree(tree, file_options(Coder::Best, 1));
    const StoredTree read = read_tree_file_bytes(write_tree_file_bytes(stored), 0, "test");
    const TreeGraph decoded = decode_stored_tree(read, 0, "test");
    const Eigen::Vector3d root = tree.origin + tree.nodes[0].position.cast<double>();
    EXPECT_LT((decoded.origin + decoded.nodes[0].position.cast<double>() - root).norm(), 1e-9);
    EXPECT_NEAR(decoded.nodes[0].radius, tree.nodes[0].radius, 0.0005 + 1e-6);
    // Every decoded vertex lies within √3·d/2 of some original vertex (d = l / r).
    const double bound = std::sqrt(3.0) * 0.1 / 5.0 / 2.0 + 1e-5;
    for (const TreeNode& node : decoded.nodes) {
        const Eigen::Vector3d p = decoded.origin + node.position.cast<double>();
        double nearest = 1e30;
        for (const TreeNode& original : tree.nodes)
            nearest = std::min(nearest, (tree.origin + original.position.cast<double>() - p).norm());
        ASSERT_LE(nearest, bound);
    }
}

TEST(TreeFile, TruncatedOrCorruptedFilesFailCleanly) {
    const std::vector<std::uint8_t> bytes = write_tree_file_bytes(store_tree(sample_tree(5, 150), file_options(Coder::Best, 3)));
    expect_damage_rejected(bytes, [](const std::vector<std::uint8_t>& b) { read_tree_file_bytes(b, -1, "t.dbf6"); });
    try {
        read_tree_file_bytes(std::vector<std::uint8_t>{'P', 'L', 'Y', '\n', 0, 0, 0, 0, 0}, 0, "x.dbf6");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("not a .dbf6 file"), std::string::npos);
    }
    std::vector<std::uint8_t> flipped = bytes;
    flipped[bytes.size() / 2] ^= 0x10;
    try {
        read_tree_file_bytes(flipped, 0, "x.dbf6");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("x.dbf6"), std::string::npos);
    }
}

TEST(ForestFile, RandomAccessPlacementAndRoundTrip) {
    std::vector<ForestTree> trees;
    for (std::uint32_t i = 0; i < 6; ++i) {
        ForestTree t;
        t.skeleton = sample_tree(10 + i, 100 + 40 * static_cast<int>(i));
        t.position = {1000.0 + 7.0 * i, 2000.0 - 3.0 * i, 0.5 * i};
        t.azimuth = 0.4f * static_cast<float>(i);
        t.name = "tree" + std::to_string(i);
        trees.push_back(std::move(t));
    }
    for (Coder coder : {Coder::Interpolative, Coder::Best}) {
        ForestStats stats;
        const std::vector<std::uint8_t> bytes = write_forest_bytes(trees, file_options(coder, 3), &stats);
        ASSERT_EQ(stats.trees.size(), trees.size());
        EXPECT_EQ(write_forest_bytes(trees, file_options(coder, 3)), bytes);  // deterministic despite threads
        ForestReader reader(bytes, "f.forest");
        ASSERT_EQ(reader.size(), trees.size());
        for (std::size_t i = trees.size(); i-- > 0;) {  // any order: records are independent
            const ForestEntry& e = reader.entry(i);
            EXPECT_EQ(e.name, trees[i].name);
            EXPECT_LT((e.position - trees[i].position).norm(), 1e-3);
            EXPECT_FLOAT_EQ(e.azimuth, trees[i].azimuth);
            const StoredTree expected = store_tree(trees[i].skeleton, file_options(coder, 3));
            for (int k = 0; k < 3; ++k) {
                const StoredTree got = reader.read(i, k);
                EXPECT_EQ(got.lods[k].symbols, expected.lods[k].symbols);
                EXPECT_EQ(got.lods[k].radii, expected.lods[k].radii);
            }
            // Placement: the tree's frame turned by its azimuth about +z, then moved to its position.
            const TreeGraph placed = reader.decode(i, 0);
            const TreeGraph local = decode_stored_tree(expected, 0, "test");
            const Eigen::Matrix3d rz = Eigen::AngleAxisd(e.azimuth, Eigen::Vector3d::UnitZ()).toRotationMatrix();
            auto world = [](const TreeGraph& t, std::size_t n) { return t.origin + t.nodes[n].position.cast<double>(); };
            for (std::size_t n : {std::size_t{0}, placed.size() / 2, placed.size() - 1}) {
                const Eigen::Vector3d expected_position = e.position + rz * world(local, n);
                EXPECT_LT((world(placed, n) - expected_position).norm(), 1e-4) << "tree " << i << " node " << n;
            }
            const Eigen::Vector3d root_in_frame = trees[i].skeleton.origin + trees[i].skeleton.nodes[0].position.cast<double>();
            EXPECT_LT((world(placed, 0) - (e.position + rz * root_in_frame)).norm(), 1e-4);
        }
        EXPECT_THROW(reader.read(trees.size()), Error);
    }
}

TEST(ForestFile, FileReaderTouchesOnlyTheRequestedRecord) {
    std::vector<ForestTree> trees(3);
    for (std::uint32_t i = 0; i < 3; ++i) {
        trees[i].skeleton = sample_tree(30 + i, 120);
        trees[i].position = {10.0 * i, 0, 0};
    }
    std::vector<std::uint8_t> bytes = write_forest_bytes(trees, file_options(Coder::Best, 1));
    ForestReader probe(bytes, "probe");
    // Damage tree 1's record: trees 0 and 2 still read, tree 1 reports its checksum.
    bytes[probe.entry(1).offset + probe.entry(1).size / 2] ^= 0x01;
    test::TempDir dir;
    const auto path = dir / "f.forest";
    {
        std::ofstream out(path, std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    }
    ForestReader reader(path);
    EXPECT_NO_THROW(reader.decode(0));
    EXPECT_NO_THROW(reader.decode(2));
    try {
        reader.decode(1);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("tree 1"), std::string::npos) << e.what();
    }
}

TEST(ForestFile, TruncatedOrCorruptedIndexFailsCleanly) {
    std::vector<ForestTree> trees(2);
    trees[0].skeleton = sample_tree(40, 80);
    trees[1].skeleton = sample_tree(41, 80);
    trees[1].position = {5, 5, 0};
    trees[1].name = "second";
    const std::vector<std::uint8_t> bytes = write_forest_bytes(trees, file_options(Coder::Interpolative, 2));
    expect_damage_rejected(bytes, [](const std::vector<std::uint8_t>& b) {
        ForestReader reader(b, "f.forest");
        for (std::size_t i = 0; i < reader.size(); ++i) reader.read(i, -1);
        if (reader.size() != 2) throw Error::input("f.forest", "tree count changed");  // a damage that went unnoticed
    });
}

TEST(ForestFile, ModelPriorIsStoredWhenItPaysAndDecodesExactly) {
    // Many trees alike: the trained prior saves more than its size, so the file carries it.
    std::vector<ForestTree> trees(40);
    for (std::uint32_t i = 0; i < trees.size(); ++i) {
        trees[i].skeleton = sample_tree(50 + i % 4, 500);
        trees[i].position = {3.0 * i, 0, 0};
    }
    const TreeFileOptions options = file_options(Coder::Best, 2);
    const std::vector<std::uint8_t> bytes = write_forest_bytes(trees, options);
    ForestReader reader(bytes, "alike.forest");
    std::size_t independent = 0;
    for (std::size_t i = 0; i < trees.size(); ++i) {
        const StoredTree expected = store_tree(trees[i].skeleton, options);
        const StoredTree got = reader.read(i, -1);
        for (std::size_t k = 0; k < expected.lods.size(); ++k) {
            ASSERT_EQ(got.lods[k].symbols, expected.lods[k].symbols);
            ASSERT_EQ(got.lods[k].radii, expected.lods[k].radii);
        }
        independent += write_tree_record(expected).size() + 4;
    }
    EXPECT_GT(reader.index_bytes(), 1000u);                       // the prior is in the index (40 entries take ~800)
    EXPECT_LT(bytes.size() - reader.index_bytes(), independent);  // and the records are smaller for it
    // A record coded with the prior cannot be read without it.
    const ForestEntry& e = reader.entry(0);
    std::size_t position = 0;
    const std::span<const std::uint8_t> record(bytes.data() + e.offset, e.size);
    EXPECT_THROW(read_tree_record(record, position, 0, "record"), Error);
}

// ForestReader::decode builds skeletons straight from the decoded internodes (the symbol text
// never exists); it must give exactly the skeleton of the chain code path, for both coders,
// every LOD, with and without the forest's model prior.
TEST(ForestFile, DecodeGivesTheSkeletonOfTheChainCodePath) {
    for (const std::size_t count : {std::size_t{3}, std::size_t{30}}) {  // 30 alike trees: the prior pays
        std::vector<ForestTree> trees(count);
        for (std::uint32_t i = 0; i < count; ++i) {
            trees[i].skeleton = sample_tree(count == 3 ? 70 + i : 50 + i % 4, 300);
            trees[i].position = {2.0 * i, 1.0, 0};
            trees[i].azimuth = 0.3f * static_cast<float>(i);
        }
        for (Coder coder : {Coder::Interpolative, Coder::Best}) {
            const std::vector<std::uint8_t> bytes = write_forest_bytes(trees, file_options(coder, 3));
            ForestReader reader(bytes, "f.forest");
            for (std::size_t i = 0; i < count; ++i)
                for (int k = 0; k < 3; ++k) {
                    const TreeGraph got = reader.decode(i, k);
                    const TreeGraph expected = place_tree(decode_stored_tree(reader.read(i, k), k, "text"), reader.entry(i));
                    ASSERT_EQ(got.size(), expected.size()) << "tree " << i << " LOD " << k;
                    EXPECT_EQ(got.origin, expected.origin);
                    for (std::size_t n = 0; n < got.size(); ++n) {
                        ASSERT_EQ(got.nodes[n].position, expected.nodes[n].position) << "tree " << i << " LOD " << k << " node " << n;
                        ASSERT_EQ(got.nodes[n].radius, expected.nodes[n].radius);
                        ASSERT_EQ(got.nodes[n].parent, expected.nodes[n].parent);
                        ASSERT_EQ(std::vector<int>(got.nodes[n].children.begin(), got.nodes[n].children.end()),
                                  std::vector<int>(expected.nodes[n].children.begin(), expected.nodes[n].children.end()));
                    }
                }
            EXPECT_THROW(reader.decode(0, 3), Error);
        }
    }
}
