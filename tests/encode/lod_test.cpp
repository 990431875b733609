// LOD reduction on the code (Pseudocode 2, Fig. 7) and the LOD thresholds of Experiment 1 (from
// the branch thicknesses).
#include "core/error.hpp"
#include "encode/hausdorff.hpp"
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"
#include "encode/tree_file.hpp"
#include "random_tree.hpp"

#include <gtest/gtest.h>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

const ChainCode kFig7{CodeKind::DBF6, "1116634617133370011637333700047", {10, 9, 5, 2, 2, 4, 2, 2, 1}};

CodeGeometry geometry(double voxel_size = 1.0) {
    CodeGeometry g;
    g.voxel_size = voxel_size;
    return g;
}

// Every vertex of `reduced` coincides with a vertex of `full` and radii and parents agree.
void expect_subtree(const TreeGraph& full, const TreeGraph& reduced) {
    ASSERT_LE(reduced.size(), full.size());
    std::vector<int> match(reduced.size(), -1);
    match[0] = 0;
    for (int node : reduced.preorder()) {
        const auto& children = reduced.nodes[node].children;
        for (std::size_t k = 0; k < children.size(); ++k) {
            const int child = children[k];
            int found = -1;
            for (int candidate : full.nodes[match[node]].children)
                if ((full.nodes[candidate].position - reduced.nodes[child].position).norm() < 1e-5f &&
                    full.nodes[candidate].radius == reduced.nodes[child].radius)
                    found = candidate;
            ASSERT_GE(found, 0) << "reduced node " << child << " has no counterpart";
            match[child] = found;
        }
    }
}

}  // namespace

TEST(Lod, Fig7VectorOfThePaper) {
    const ChainCode reduced = reduce_lod(kFig7, 3.0);
    EXPECT_EQ(reduced.symbols, "11186348170011837");
    EXPECT_EQ(reduced.radii, (std::vector<int>{10, 9, 5, 2, 4, 2}));
    EXPECT_EQ(reduced.kind, CodeKind::DBF6);
}

TEST(Lod, ThresholdAtOrBelowTheSmallestRadiusKeepsEverything) {
    EXPECT_EQ(reduce_lod(kFig7, 1.0).symbols, kFig7.symbols);
    EXPECT_EQ(reduce_lod(kFig7, 0.0).radii, kFig7.radii);
}

TEST(Lod, TrunkAndMainExtensionsAreNeverPruned) {
    // Everything below 100: only the trunk (the first branch) stays, down to its radius-2 tip.
    const ChainCode reduced = reduce_lod(kFig7, 100.0);
    EXPECT_EQ(reduced.symbols, "1118834817");
    EXPECT_EQ(reduced.radii, (std::vector<int>{10, 9, 5, 2}));
}

TEST(Lod, BranchesOfAPrunedParentArePrunedEvenWhenThick) {
    // Trunk forks into lateral L (radius 2) whose own lateral M has radius 6 >= T = 3. M cannot
    // survive without L (the printed Pseudocode 2 would copy it and break the code).
    const ChainCode code{CodeKind::F6, "2262270060072227", {9, 8, 2, 2, 6}};
    const ChainCode reduced = reduce_lod(code, 3.0);
    EXPECT_EQ(reduced.symbols, "228227");
    EXPECT_EQ(reduced.radii, (std::vector<int>{9, 8}));
}

TEST(Lod, MultiWayForkSiblingsArePrunedIndividually) {
    // Three-way fork: main, first lateral (radius 3) and second lateral (radius 2) announced by the
    // zero-length internode "6" carrying radius 3.
    const ChainCode code{CodeKind::F6, "2262276007337", {8, 5, 3, 3, 2}};
    const ChainCode t3 = reduce_lod(code, 3.0);
    EXPECT_EQ(t3.symbols, "2262278007");  // the zero-length internode's fork becomes 8
    EXPECT_EQ(t3.radii, (std::vector<int>{8, 5, 3, 3}));
    const TreeGraph decoded = decode_tree(t3, geometry());
    EXPECT_EQ(decoded.size(), 4u);  // root, fork, main, first lateral: the zero-length internode is contracted
    EXPECT_EQ(decoded.nodes[1].children.size(), 2u);
    const ChainCode t4 = reduce_lod(code, 4.0);
    EXPECT_EQ(t4.symbols, "228227");
    EXPECT_EQ(t4.radii, (std::vector<int>{8, 5}));
}

TEST(Lod, ReducedCodesDecodeToSubtreesOfTheFullTree) {
    const TreeGraph full = decode_tree(kFig7, geometry());
    for (double threshold : {2.0, 3.0, 4.5, 5.0, 11.0}) {
        const ChainCode reduced = reduce_lod(kFig7, threshold);
        const TreeGraph tree = decode_tree(reduced, geometry());
        expect_subtree(full, tree);
        // Every remaining lateral starts at or above the threshold.
        for (int node : tree.preorder())
            for (std::size_t k = 1; k < tree.nodes[node].children.size(); ++k)
                EXPECT_GE(tree.nodes[tree.nodes[node].children[k]].radius * 1000.0f, threshold - 1e-3);
    }
}

TEST(Lod, ThresholdsSitAtUniformPositionsOfTheSortedUniqueBranchThicknesses) {
    // Fig. 7: the trunk (radii 10 9 5 2), then four laterals whose first internodes are 2, 4, 2, 1.
    EXPECT_EQ(branch_thicknesses(kFig7), (std::vector<int>{2, 4, 2, 1}));
    // Unique thicknesses 1 2 4 (n = 3), 3 LODs: positions 3/3, 6/3 -> 1, 2.
    EXPECT_EQ(lod_thresholds(branch_thicknesses(kFig7), 3), (std::vector<double>{2, 4}));
    // Any list: unique 1 2 4 5 9 10 (n = 6), 4 LODs: positions 6/4, 12/4, 18/4 -> 1, 3, 4.
    EXPECT_EQ(lod_thresholds(kFig7.radii, 4), (std::vector<double>{2, 5, 9}));
    EXPECT_EQ(lod_thresholds(kFig7.radii, 1), std::vector<double>{});
    EXPECT_EQ(lod_thresholds({3, 3, 3}, 3), (std::vector<double>{3, 3}));
    EXPECT_THROW(lod_thresholds({1}, 0), Error);
}

// A thick trunk with thin laterals of eight thicknesses: thresholds from every radius (the
// trunk's many values among them) would lie above every lateral from LOD 2 on, and LOD 3 would
// be LOD 2 again; from the branch thicknesses each LOD prunes more than the one before.
TEST(Lod, EachLodPrunesMoreWhenTheTrunkIsThick) {
    TreeGraph tree;
    tree.add_node({0, 0, 0}, 0.40f, -1);
    for (int i = 1; i <= 40; ++i) tree.add_node({0, 0, 0.25f * static_cast<float>(i)}, 0.40f - 0.008f * static_cast<float>(i), i - 1);
    for (int b = 0; b < 8; ++b) {
        const float angle = 0.8f * static_cast<float>(b);
        int parent = 4 * b + 4;
        for (int k = 1; k <= 4; ++k)
            parent = tree.add_node(tree.nodes[4 * b + 4].position +
                                           0.25f * static_cast<float>(k) * Eigen::Vector3f(std::cos(angle), std::sin(angle), 0.5f),
                                   0.01f * static_cast<float>(b + 1) - 0.001f * static_cast<float>(k), parent);
    }
    TreeFileOptions options;
    options.lods = 4;
    const StoredTree stored = store_tree(tree, options, "thick trunk");
    ASSERT_EQ(stored.lods.size(), 4u);
    for (std::size_t k = 1; k < stored.lods.size(); ++k) EXPECT_LT(stored.lods[k].radii.size(), stored.lods[k - 1].radii.size()) << k;
    const EncodedTree encoded = encode_tree(tree, options.encode);
    const std::vector<ChainCode> by_every_radius = lod_chain(encoded.code, lod_thresholds(encoded.code.radii, 4));
    EXPECT_EQ(by_every_radius[3].radii.size(), by_every_radius[2].radii.size());  // what the thresholds were before
}

TEST(Lod, SuccessiveReductionEqualsDirectReduction) {
    test::RandomTreeProfile profile;
    profile.max_laterals = 3;
    profile.max_nodes = 400;
    for (std::uint32_t seed = 1; seed <= 40; ++seed) {
        EncodeOptions options;
        options.internode_length = profile.internode_length;
        const EncodedTree encoded = encode_tree(test::random_tree(profile, seed), options);
        const std::vector<double> thresholds = lod_thresholds(encoded.code.radii, 4);
        const std::vector<ChainCode> chain = lod_chain(encoded.code, thresholds);
        ASSERT_EQ(chain.size(), 4u);
        for (std::size_t k = 1; k < chain.size(); ++k) {
            const ChainCode direct = reduce_lod(encoded.code, thresholds[k - 1]);
            EXPECT_EQ(chain[k].symbols, direct.symbols);
            EXPECT_EQ(chain[k].radii, direct.radii);
            EXPECT_LE(chain[k].symbols.size(), chain[k - 1].symbols.size());
            expect_subtree(decode_tree(chain[k - 1], encoded.geometry), decode_tree(chain[k], encoded.geometry));
        }
    }
}

TEST(Lod, F6AndDbf6PruneTheSameBranches) {
    test::RandomTreeProfile profile;
    profile.max_laterals = 2;
    profile.wiggle_degrees = 10;
    for (std::uint32_t seed = 100; seed < 120; ++seed) {
        EncodeOptions options;
        options.internode_length = profile.internode_length;
        const EncodedTree encoded = encode_tree(test::random_tree(profile, seed), options);
        ChainCode f6 = encoded.code;
        f6.kind = CodeKind::F6;
        f6.symbols = write_symbols(encoded.internodes, CodeKind::F6);
        for (double threshold : lod_thresholds(encoded.code.radii, 4)) {
            const TreeGraph a = decode_tree(reduce_lod(encoded.code, threshold), encoded.geometry);
            const TreeGraph b = decode_tree(reduce_lod(f6, threshold), encoded.geometry);
            ASSERT_EQ(a.size(), b.size());
            for (std::size_t i = 0; i < a.size(); ++i) {
                EXPECT_EQ(a.nodes[i].position, b.nodes[i].position);
                EXPECT_EQ(a.nodes[i].children, b.nodes[i].children);
            }
        }
    }
}
