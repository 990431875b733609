// The coding rules of Strnad et al. 2020, §3.1, one by one: Table 1 moves, Eq. 1 rounding, the paper's Fig. 4 /
// Fig. 6 vectors, the main-child rule and its tie-breaks, multi-way forks, the root fork, and
// contraction of zero-length internodes.
#include "core/error.hpp"
#include "encode/chain_code.hpp"
#include "encode/hausdorff.hpp"
#include "encode/tree_code.hpp"
#include "paper_trees.hpp"

#include <gtest/gtest.h>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

std::string moves(int x, int y, int z) {
    std::string out;
    append_moves(Voxel(x, y, z), out);
    return out;
}

EncodedTree encode_with(const TreeGraph& tree, CodeKind kind, double resolution, double length) {
    EncodeOptions options;
    options.kind = kind;
    options.resolution = resolution;
    options.internode_length = length;
    return encode_tree(tree, options);
}

CodeGeometry geometry_of(double voxel_size, int root_radius = 0) {
    CodeGeometry geometry;
    geometry.voxel_size = voxel_size;
    geometry.root_radius = root_radius;
    return geometry;
}

// A small tree built from voxel coordinates with voxel size 1 (l = 2, r = 2).
struct Builder {
    TreeGraph tree;
    Builder() { tree.add_node({0, 0, 0}, 0.010f, -1); }
    int add(int parent, float x, float y, float z, float radius_mm) { return tree.add_node({x, y, z}, radius_mm * 0.001f, parent); }
};

}  // namespace

TEST(ChainCode, MovesAreWrittenInAscendingSymbolOrder) {
    EXPECT_EQ(moves(2, 1, -3), "001555");  // the paper's example (§3.1)
    EXPECT_EQ(moves(-1, 2, 0), "113");
    EXPECT_EQ(moves(0, 0, 0), "");
    EXPECT_EQ(moves(-2, -1, 1), "2334");
}

TEST(ChainCode, VoxelizationRoundsHalfAwayFromZero) {
    EXPECT_EQ(voxelize(0.0), 0);
    EXPECT_EQ(voxelize(0.49), 0);
    EXPECT_EQ(voxelize(0.5), 1);
    EXPECT_EQ(voxelize(-0.5), -1);
    EXPECT_EQ(voxelize(1.49), 1);
    EXPECT_EQ(voxelize(-1.5), -2);
    EXPECT_EQ(voxelize(2.5), 3);
    EXPECT_EQ(voxelize(-2.49), -2);
}

TEST(ChainCode, Fig4SkeletonGivesThePapersF6AndDbf6Codes) {
    const TreeGraph tree = test::fig4_tree();
    const EncodedTree f6 = encode_with(tree, CodeKind::F6, test::kFig4Resolution, test::kFig4InternodeLength);
    const EncodedTree dbf6 = encode_with(tree, CodeKind::DBF6, test::kFig4Resolution, test::kFig4InternodeLength);
    EXPECT_EQ(f6.code.symbols, test::kFig4F6);
    EXPECT_EQ(dbf6.code.symbols, test::kFig4DBF6);
    const std::vector<int> radii{10, 9, 6, 3, 4, 3, 2, 1};  // code order, child-vertex radii in mm
    EXPECT_EQ(f6.code.radii, radii);
    EXPECT_EQ(dbf6.code.radii, radii);
    EXPECT_EQ(dbf6.geometry.root_radius, 12);
}

TEST(ChainCode, Fig4CodesDecodeAndReencodeToTheSameStrings) {
    const TreeGraph original = test::fig4_tree();
    for (const CodeKind kind : {CodeKind::F6, CodeKind::DBF6}) {
        ChainCode code;
        code.kind = kind;
        code.symbols = kind == CodeKind::F6 ? test::kFig4F6 : test::kFig4DBF6;
        code.radii = {10, 9, 6, 3, 4, 3, 2, 1};
        const double d = test::kFig4InternodeLength / test::kFig4Resolution;
        const TreeGraph decoded = decode_tree(code, geometry_of(d, 12));
        ASSERT_EQ(decoded.size(), 9u);
        EXPECT_EQ(decoded.tip_count(), 4u);
        EXPECT_EQ(encode_with(decoded, kind, test::kFig4Resolution, test::kFig4InternodeLength).code.symbols, code.symbols);
        // Voxel centres: v4 of the figure is at (-2, 11, 0) voxels from the root.
        EXPECT_NEAR(decoded.nodes[4].position.x(), -2 * d, 1e-6);
        EXPECT_NEAR(decoded.nodes[4].position.y(), 11 * d, 1e-6);
        // Same shape as the original up to the voxel bound (the original's root is elsewhere).
        TreeGraph shifted = decoded;
        for (auto& node : shifted.nodes) node.position += original.nodes[0].position;
        const EncodedTree encoded = encode_with(original, kind, test::kFig4Resolution, test::kFig4InternodeLength);
        const auto check = check_vertex_error(original, shifted, encoded.decoded_to_source, d);
        EXPECT_TRUE(check.within_bound) << check.max_error << " > " << check.bound;
    }
}

TEST(ChainCode, DecodedChildrenComeMainFirstAndDecodedNodesInCodeOrder) {
    ChainCode code{CodeKind::DBF6, test::kFig4DBF6, {10, 9, 6, 3, 4, 3, 2, 1}};
    const TreeGraph decoded = decode_tree(code, geometry_of(1.0));
    // Code order: v1 v2 v3 v4 v5 v6 v7 v8 -> nodes 1..8; v2 forks into v3 (main) and v5.
    EXPECT_EQ(decoded.nodes[2].children, (std::vector<int>{3, 5}));
    EXPECT_EQ(decoded.nodes[3].children, (std::vector<int>{4, 7}));
    EXPECT_EQ(decoded.nodes[5].children, (std::vector<int>{6, 8}));
    EXPECT_FLOAT_EQ(decoded.nodes[5].radius, 0.004f);
}

TEST(ChainCode, MainChildIsTheThickestEvenWhenItTurnsMore) {
    Builder b;
    const int fork = b.add(0, 0, 0, 2, 8);
    b.add(fork, 0, 0, 4, 3);  // straight on, thinner
    b.add(fork, 2, 0, 2, 5);  // right angle, thicker: main
    const auto code = encode_with(b.tree, CodeKind::F6, 2, 2).code;
    EXPECT_EQ(code.symbols, "226007227");
    EXPECT_EQ(code.radii, (std::vector<int>{8, 5, 3}));
}

TEST(ChainCode, EqualRadiiGoToTheSmallestDirectionChange) {
    Builder b;
    const int fork = b.add(0, 0, 0, 2, 8);
    b.add(fork, 2, 0, 3, 4);  // lower index, turns more
    b.add(fork, 0, 1, 4, 4);  // nearly straight: main
    EXPECT_EQ(encode_with(b.tree, CodeKind::F6, 2, 2).code.symbols, "22612270027");
}

TEST(ChainCode, EqualRadiiAndTurnsGoToTheLowestIndex) {
    Builder b;
    const int fork = b.add(0, 0, 0, 2, 8);
    const int left = b.add(fork, -1, 0, 3, 4);
    const int right = b.add(fork, 1, 0, 3, 4);
    // Store the children in the other order: the encoder must not rely on it.
    std::swap(b.tree.nodes[fork].children[0], b.tree.nodes[fork].children[1]);
    ASSERT_LT(left, right);
    EXPECT_EQ(encode_with(b.tree, CodeKind::F6, 2, 2).code.symbols, "226237027");
}

TEST(ChainCode, ThreeWayForkEmitsOneZeroLengthInternodePerSibling) {
    Builder b;
    const int fork = b.add(0, 0, 0, 2, 8);
    b.add(fork, 0, 0, 4, 5);   // main
    b.add(fork, -2, 0, 2, 2);  // second lateral (thinner)
    b.add(fork, 2, 0, 2, 3);   // first lateral
    const auto f6 = encode_with(b.tree, CodeKind::F6, 2, 2);
    EXPECT_EQ(f6.code.symbols, "2262276007337");
    // The zero-length internode carries the first lateral's radius.
    EXPECT_EQ(f6.code.radii, (std::vector<int>{8, 5, 3, 3, 2}));
    EXPECT_EQ(encode_with(b.tree, CodeKind::DBF6, 2, 2).code.symbols, "22676007337");
}

TEST(ChainCode, FourWayForkQueuesSiblingsInRadiusOrder) {
    Builder b;
    const int fork = b.add(0, 0, 0, 2, 8);
    b.add(fork, 0, 2, 2, 2);   // third lateral
    b.add(fork, 0, 0, 4, 5);   // main
    b.add(fork, -2, 0, 2, 3);  // second lateral
    b.add(fork, 2, 0, 2, 4);   // first lateral
    const auto encoded = encode_with(b.tree, CodeKind::F6, 2, 2);
    EXPECT_EQ(encoded.code.symbols, "22622766007337117");
    EXPECT_EQ(encoded.code.radii, (std::vector<int>{8, 5, 4, 4, 4, 3, 2}));
    // Decoding restores the four-way fork, main first, laterals by decreasing radius.
    const TreeGraph decoded = decode_tree(encoded.code, geometry_of(1.0));
    ASSERT_EQ(decoded.size(), 6u);
    ASSERT_EQ(decoded.nodes[1].children.size(), 4u);
    std::vector<float> radii;
    for (int child : decoded.nodes[1].children) radii.push_back(decoded.nodes[child].radius);
    EXPECT_EQ(radii, (std::vector<float>{0.005f, 0.004f, 0.003f, 0.002f}));
    EXPECT_EQ(encoded.decoded_to_source, (std::vector<int>{0, 1, 3, 5, 4, 2}));
}

TEST(ChainCode, RootWithSeveralChildrenStartsWithAZeroLengthFork) {
    Builder b;
    b.add(0, 0, 0, 2, 5);  // trunk
    b.add(0, 2, 0, 0, 3);
    const auto f6 = encode_with(b.tree, CodeKind::F6, 2, 2);
    EXPECT_EQ(f6.code.symbols, "6227007");
    EXPECT_EQ(f6.code.radii, (std::vector<int>{5, 5, 3}));
    EXPECT_EQ(encode_with(b.tree, CodeKind::DBF6, 2, 2).code.symbols, "6227007");
    const TreeGraph decoded = decode_tree(f6.code, geometry_of(1.0, 10));
    ASSERT_EQ(decoded.size(), 3u);
    EXPECT_EQ(decoded.nodes[0].children, (std::vector<int>{1, 2}));
    EXPECT_FLOAT_EQ(decoded.nodes[0].radius, 0.010f);
}

TEST(ChainCode, Dbf6CodesOnlyCorrectionsAlongAChain) {
    Builder b;
    int node = 0;
    for (int k = 1; k <= 4; ++k) node = b.add(node, 0, 0, 2.0f * k, 9 - k);
    node = b.add(node, 1, 0, 10, 4);  // a bend: correction +x
    EXPECT_EQ(encode_with(b.tree, CodeKind::F6, 2, 2).code.symbols, "2282282282280227");
    EXPECT_EQ(encode_with(b.tree, CodeKind::DBF6, 2, 2).code.symbols, "22888807");
}

TEST(ChainCode, ZeroLengthBranchStartsAreContractedConsistently) {
    // A lateral whose first internode stays in the fork's voxel and forks again: the code is
    // the same as a three-way fork, so the decoder contracts it and the node map says so.
    Builder b;
    const int fork = b.add(0, 0, 0, 2, 8);
    b.add(fork, 0, 0, 4, 5);
    const int stub = b.add(fork, 0.1f, 0, 2, 4);  // within the fork's voxel
    b.add(stub, 2, 0, 2, 3);
    b.add(stub, -2, 0, 2, 2);
    const auto encoded = encode_with(b.tree, CodeKind::DBF6, 2, 2);
    const TreeGraph decoded = decode_tree(encoded.code, geometry_of(1.0));
    EXPECT_EQ(decoded.size(), b.tree.size() - 1);
    ASSERT_EQ(encoded.decoded_to_source.size(), decoded.size());
    EXPECT_EQ(std::count(encoded.decoded_to_source.begin(), encoded.decoded_to_source.end(), stub), 0);
    TreeGraph shifted = decoded;
    const auto check = check_vertex_error(b.tree, shifted, encoded.decoded_to_source, 1.0);
    EXPECT_TRUE(check.within_bound);
    // A zero-length tip is a node of its own and stays.
    Builder tip;
    const int f = tip.add(0, 0, 0, 2, 8);
    tip.add(f, 0, 0, 4, 5);
    tip.add(f, 0.2f, 0, 2, 4);
    const auto tip_code = encode_with(tip.tree, CodeKind::DBF6, 2, 2);
    EXPECT_EQ(tip_code.code.symbols, "22677");
    EXPECT_EQ(decode_tree(tip_code.code, geometry_of(1.0)).size(), 4u);
}

TEST(ChainCode, InvalidTreesAndOptionsAreRejected) {
    Builder b;
    EXPECT_THROW(encode_with(b.tree, CodeKind::DBF6, 2, 2), Error);  // root only: no internodes
    b.add(0, 0, 0, 2, 5);
    try {
        encode_with(b.tree, CodeKind::DBF6, 0, 2);
        FAIL() << "resolution 0 accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::Usage);
    }
    b.tree.nodes[1].radius = -0.01f;
    try {
        encode_with(b.tree, CodeKind::DBF6, 2, 2);
        FAIL() << "negative radius accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("negative radius"), std::string::npos);
    }
}

TEST(ChainCode, AutoInternodeLengthIsTheMedianEdge) {
    Builder b;
    int node = 0;
    const float lengths[] = {1.0f, 3.0f, 2.0f, 0.0f, 2.5f};
    float z = 0;
    for (float length : lengths) node = b.add(node, 0, 0, z += length, 1);
    EXPECT_DOUBLE_EQ(median_internode_length(b.tree), 2.5);  // zero-length edges are ignored
    EncodeOptions options;
    options.resolution = 5;
    EXPECT_DOUBLE_EQ(encode_tree(b.tree, options).geometry.voxel_size, 0.5);
}
