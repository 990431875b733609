// decode(encode(t)) on 1,000 random trees (bifurcations and multi-way forks, straight and
// wiggly, single trunk and multi-stemmed): same topology, radii and voxel positions, every vertex
// within √3·d/2 of the original, main children first, and encoding again gives the same code.
#include "encode/chain_code.hpp"
#include "encode/hausdorff.hpp"
#include "encode/tree_code.hpp"
#include "random_tree.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

struct Case {
    test::RandomTreeProfile profile;
    EncodeOptions options;
};

// A varied case per seed: shape, fork multiplicity, wiggle, root stems, resolution, kind.
Case make_case(std::uint32_t seed) {
    test::TreeRandom random(seed * 7919u + 17u);
    Case c;
    c.profile.max_nodes = 10 + random.below(300);
    c.profile.max_laterals = random.uniform() < 0.5 ? 1 : 2 + random.below(3);
    c.profile.wiggle_degrees = random.uniform() < 0.3 ? 0.0 : random.uniform(2.0, 25.0);
    c.profile.fork_probability = random.uniform(0.1, 0.5);
    c.profile.root_stems = random.uniform() < 0.8 ? 1 : 2 + random.below(3);
    c.profile.trunk_internodes = 5 + random.below(30);
    c.profile.tip_radius = random.uniform(0.0005, 0.004);
    const double resolutions[] = {3.0, 4.0, 5.0, 7.5, 10.0};
    c.options.resolution = resolutions[random.below(5)];
    // Nominal l, or the median edge (auto) where r >= 5 keeps every edge longer than a voxel.
    c.options.internode_length = c.options.resolution >= 5.0 && random.uniform() < 0.3 ? 0.0 : c.profile.internode_length;
    c.options.kind = random.uniform() < 0.5 ? CodeKind::F6 : CodeKind::DBF6;
    return c;
}

// Eq. 1 written independently of the encoder: std::round rounds halves away from zero.
Eigen::Vector3d expected_voxel_centre(const TreeGraph& tree, int node, double d) {
    const Eigen::Vector3d root = tree.nodes[0].position.cast<double>();
    const Eigen::Vector3d p = tree.nodes[node].position.cast<double>() - root;
    return root + d * Eigen::Vector3d(std::round(p.x() / d), std::round(p.y() / d), std::round(p.z() / d));
}

std::size_t extra_children(const TreeGraph& tree) {
    std::size_t forks = 0;
    for (const auto& node : tree.nodes)
        if (node.children.size() > 1) forks += node.children.size() - 1;
    return forks;
}

// Checks one tree; returns the F6 and DBF6 lengths for the aggregate checks.
std::pair<std::size_t, std::size_t> check_round_trip(const TreeGraph& tree, const EncodeOptions& options, std::uint32_t seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const EncodedTree encoded = encode_tree(tree, options);
    const double d = encoded.geometry.voxel_size;
    const TreeGraph decoded = decode_tree(encoded.code, encoded.geometry);

    // Symbols: one 7 per tip, one 6 per extra child of a vertex, one radius per internode.
    const SymbolCounts counts = count_symbols(encoded.code.symbols);
    EXPECT_EQ(counts.tips, tree.tip_count());
    EXPECT_EQ(counts.forks, extra_children(tree));
    EXPECT_EQ(encoded.code.radii.size(), counts.internodes);

    // Topology: the node map is a bijection under which parents correspond.
    const std::vector<int>& source = encoded.decoded_to_source;
    EXPECT_EQ(decoded.size(), tree.size());
    if (decoded.size() != tree.size() || source.size() != tree.size()) return {0, 0};
    EXPECT_EQ(std::set<int>(source.begin(), source.end()).size(), tree.size());
    EXPECT_EQ(source[0], 0);
    for (std::size_t k = 1; k < decoded.size(); ++k) {
        const TreeNode& node = decoded.nodes[k];
        const TreeNode& original = tree.nodes[source[k]];
        EXPECT_EQ(source[node.parent], original.parent) << "node " << k;
        // Radii quantized to the radius unit.
        EXPECT_EQ(std::lround(node.radius / options.radius_unit), std::lround(original.radius / options.radius_unit));
        // Voxel centres of Eq. 1, and within √3·d/2 of the original.
        const Eigen::Vector3d centre = expected_voxel_centre(tree, source[k], d);
        EXPECT_LT((node.position.cast<double>() - centre).norm(), 1e-5 * (1.0 + centre.norm())) << "node " << k;
        EXPECT_LE((node.position - original.position).norm(), std::sqrt(3.0) * d / 2.0 + 1e-5) << "node " << k;
    }
    EXPECT_TRUE(check_vertex_error(tree, decoded, source, d).within_bound);

    // Main child first: children sorted by non-increasing radius (ties broken by the rule, not checked here).
    for (const TreeNode& node : decoded.nodes)
        for (std::size_t k = 1; k < node.children.size(); ++k)
            EXPECT_GE(decoded.nodes[node.children[k - 1]].radius, decoded.nodes[node.children[k]].radius);

    // Encoding the decoded tree again reproduces the code; the other kind decodes identically.
    EncodeOptions again = options;
    again.internode_length = encoded.internode_length;
    const EncodedTree reencoded = encode_tree(decoded, again);
    EXPECT_EQ(reencoded.code.symbols, encoded.code.symbols);
    EXPECT_EQ(reencoded.code.radii, encoded.code.radii);
    const CodeKind other = options.kind == CodeKind::F6 ? CodeKind::DBF6 : CodeKind::F6;
    const ChainCode other_code{other, write_symbols(encoded.internodes, other), encoded.code.radii};
    const TreeGraph other_decoded = decode_tree(other_code, encoded.geometry);
    EXPECT_EQ(other_decoded.size(), decoded.size());
    for (std::size_t k = 0; k < std::min(decoded.size(), other_decoded.size()); ++k)
        EXPECT_EQ(other_decoded.nodes[k].position, decoded.nodes[k].position);

    const std::size_t f6 = options.kind == CodeKind::F6 ? encoded.code.symbols.size() : other_code.symbols.size();
    const std::size_t dbf6 = options.kind == CodeKind::DBF6 ? encoded.code.symbols.size() : other_code.symbols.size();
    return {f6, dbf6};
}

}  // namespace

TEST(RoundTrip, ThousandRandomTrees) {
    std::size_t straight_f6 = 0, straight_dbf6 = 0, multiway = 0, multistem = 0;
    for (std::uint32_t seed = 1; seed <= 1000; ++seed) {
        const Case c = make_case(seed);
        const TreeGraph tree = test::random_tree(c.profile, seed);
        const auto [f6, dbf6] = check_round_trip(tree, c.options, seed);
        if (c.profile.wiggle_degrees == 0.0) {
            straight_f6 += f6;
            straight_dbf6 += dbf6;
        }
        for (const auto& node : tree.nodes) multiway += node.children.size() > 2;
        multistem += tree.nodes[0].children.size() > 1;
        if (::testing::Test::HasFailure()) break;  // one failing seed is enough to read
    }
    // The generator did produce what the test claims to cover.
    EXPECT_GT(multiway, 500u);
    EXPECT_GT(multistem, 100u);
    // Straight branches are where DBF6 pays off most (§3.1).
    EXPECT_LT(static_cast<double>(straight_dbf6), 0.75 * static_cast<double>(straight_f6));
}

TEST(RoundTrip, HausdorffOfFullDetailDecodingIsWithinTheVoxelBound) {
    test::RandomTreeProfile profile;
    profile.max_nodes = 500;
    profile.max_laterals = 3;
    profile.wiggle_degrees = 12;
    for (double r : {3.0, 5.0, 10.0}) {
        EncodeOptions options;
        options.resolution = r;
        options.internode_length = profile.internode_length;
        const TreeGraph tree = test::random_tree(profile, 77);
        const EncodedTree encoded = encode_tree(tree, options);
        const auto h = skeleton_hausdorff(tree, decode_tree(encoded.code, encoded.geometry));
        const double bound = std::sqrt(3.0) * encoded.geometry.voxel_size / 2.0;
        EXPECT_LE(h.max, bound + 1e-5) << "r = " << r;
        EXPECT_GT(h.max, 0.0);
        EXPECT_LT(h.mean, h.max);
    }
}
