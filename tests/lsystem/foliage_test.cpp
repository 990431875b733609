// Foliage of Lluch et al. 2010, via Ong's seminar report, §3.2: leaf blades, the bounding-box hierarchy that follows the branching,
// the volume threshold, the combined LOD bookkeeping, and the diagonal-plane textures (render/).
#include "lsystem/foliage.hpp"
#include "lsystem/lsystem.hpp"
#include "lsystem/multires_chain.hpp"
#include "lsystem_test_util.hpp"
#include "render/foliage_textures.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

using namespace treelobes;
using namespace treelobes::lsystem;
using treelobes::lsystem::test_util::example;

namespace {

struct Drawn {
    Tadt tadt;
    TurtleResult turtle;
};

Drawn draw(const std::string& text) {
    const ModuleString string = parse_module_string(text);
    return {build_tadt(string), interpret(string)};
}

// Leafy ternary tree after `steps` steps: string, tADT, turtle output.
struct LeafyTree {
    ModuleString string;
    TurtleOptions turtle;
};
LeafyTree leafy_tree(int steps) {
    const LSystem system = load_lsystem(example("leafy_ternary.lsys"));
    DeriveOptions options;
    options.steps = steps;
    return {apply_homomorphism(system, derive(system, options)), system.turtle};
}

bool contains(const Eigen::AlignedBox3d& outer, const Eigen::AlignedBox3d& inner) {
    return (outer.min().array() <= inner.min().array() + 1e-9).all() && (inner.max().array() <= outer.max().array() + 1e-9).all();
}

}  // namespace

TEST(Foliage, LeafOutlineFollowsTheTurtleFrame) {
    LeafPlacement leaf;
    leaf.position = {1, 2, 3};
    leaf.heading = {0, 0, 1};
    leaf.up = {-1, 0, 0};  // L = U x H = +y
    leaf.size = 2.0f;
    const auto outline = leaf_outline(leaf, {.width_ratio = 0.5});
    EXPECT_TRUE(outline[0].isApprox(Eigen::Vector3f(1, 2, 3)));
    EXPECT_TRUE(outline[3].isApprox(Eigen::Vector3f(1, 2, 5)));        // tip: base + size * H
    EXPECT_TRUE(outline[2].isApprox(Eigen::Vector3f(1, 2.5f, 3.8f)));  // widest at 40 %: half width 0.5
    EXPECT_TRUE(outline[4].isApprox(Eigen::Vector3f(1, 1.5f, 3.8f)));
    for (const auto& p : outline) EXPECT_FLOAT_EQ(p.x(), 1.0f);  // flat, normal U
    const TriangleMesh mesh = foliage_mesh(std::vector<LeafPlacement>{leaf, leaf});
    EXPECT_EQ(mesh.vertex_count(), 12u);
    EXPECT_EQ(mesh.face_count(), 8u);
    // Hexagon (0,0) (0.3,±0.3) (0.8,±0.5) (2,0) in (H, L) units: area 1.09 per blade.
    EXPECT_NEAR(mesh.area(), 2 * 1.09, 1e-5);
}

TEST(Foliage, HierarchyFollowsTheBranching) {
    // n0 F(1); n1 [+F L]; n2 [-F ...] with n3 [&F L] and continuation n4 F L; n5 F(2) without leaves.
    const Drawn d = draw("F(1)[+(90)F(1)L(0.1)][-(90)F(1)[&(90)F(1)L(0.1)]F(1)L(0.1)]F(2)");
    ASSERT_EQ(d.tadt.nodes.size(), 6u);
    ASSERT_EQ(d.turtle.leaves.size(), 3u);
    const FoliageHierarchy h = build_foliage_hierarchy(d.tadt, d.turtle.leaves);
    ASSERT_EQ(h.boxes.size(), 5u);
    EXPECT_EQ(h.box_of_node, (std::vector<int>{0, 1, 2, 3, 4, -1}));
    const std::vector<int> parents{-1, 0, 0, 2, 2}, depths{0, 1, 1, 2, 2};
    const std::vector<std::size_t> begins{0, 0, 1, 1, 2}, ends{3, 1, 3, 2, 3};
    for (std::size_t b = 0; b < h.boxes.size(); ++b) {
        EXPECT_EQ(h.boxes[b].parent, parents[b]) << b;
        EXPECT_EQ(h.boxes[b].depth, depths[b]) << b;
        EXPECT_EQ(h.boxes[b].leaf_begin, begins[b]) << b;
        EXPECT_EQ(h.boxes[b].leaf_end, ends[b]) << b;
        EXPECT_EQ(h.boxes[b].tadt_node, static_cast<int>(b));
    }
    EXPECT_EQ(h.boxes[0].children, (std::vector<int>{1, 2}));
    EXPECT_EQ(h.boxes[2].children, (std::vector<int>{3, 4}));
    EXPECT_EQ(h.boxes[4].own_leaves, 1u);
    EXPECT_EQ(h.boxes[2].own_leaves, 0u);
    EXPECT_EQ(h.max_depth(), 2);
    EXPECT_DOUBLE_EQ(h.boxes[0].volume_ratio, 1.0);
}

TEST(Foliage, LeaflessLinksShareTheirChildsBox) {
    // n1 (+F) has no leaves of its own and one leafy child n2: both use one box.
    const Drawn d = draw("F(1)[+(90)F(1)[-(30)F(1)L(0.1)]]F(1)L(0.1)");
    const FoliageHierarchy h = build_foliage_hierarchy(d.tadt, d.turtle.leaves);
    ASSERT_EQ(h.boxes.size(), 3u);
    EXPECT_EQ(h.box_of_node, (std::vector<int>{0, 1, 1, 2}));
    EXPECT_EQ(h.boxes[1].tadt_node, 2);
    EXPECT_EQ(h.boxes[1].parent, 0);
    EXPECT_EQ(h.boxes[1].depth, 1);
}

TEST(Foliage, LeafOnlyBracketsAreOrnamentsOfTheirNode) {
    // n1 [+F(1) ...] carries two leaf brackets n2, n3 (no F: ornaments) and no sub-branch.
    const Drawn d = draw("F(1)[+(90)F(1)[&(30)L(0.1)][^(30)L(0.1)]]F(1)L(0.1)");
    ASSERT_EQ(d.tadt.nodes.size(), 5u);
    FoliageOptions options;
    options.texture_threshold = 0.0;
    const FoliageHierarchy h = build_foliage_hierarchy(d.tadt, d.turtle.leaves, options);
    EXPECT_EQ(h.ornament, (std::vector<char>{0, 0, 1, 1, 0}));
    ASSERT_EQ(h.boxes.size(), 3u);
    EXPECT_EQ(h.box_of_node, (std::vector<int>{0, 1, -1, -1, 2}));
    EXPECT_EQ(h.boxes[1].own_leaves, 2u);
    EXPECT_EQ(h.boxes[1].leaf_count(), 2u);
    EXPECT_EQ(h.boxes[0].own_leaves, 0u);
    // Prefix {n0, n1}: the ornaments' leaves come with n1, n4's leaf is in its box's textures.
    const FoliageLod f = foliage_for_prefix(d.tadt, h, {1, 1, 0, 0, 0});
    EXPECT_EQ(f.attached_leaves, (std::vector<std::size_t>{0, 1}));
    EXPECT_EQ(f.textured_boxes, std::vector<int>{2});
    EXPECT_EQ(f.leaves_in_textures, 1u);
    // Prefix {n0}: n1 and its ornaments are one textured sub-branch.
    const FoliageLod g = foliage_for_prefix(d.tadt, h, {1, 0, 0, 0, 0});
    EXPECT_TRUE(g.attached_leaves.empty());
    EXPECT_EQ(g.textured_boxes, (std::vector<int>{1, 2}));
    EXPECT_EQ(g.leaves_in_textures, 3u);
}

TEST(Foliage, BoxesNestAndBoundTheirBlades) {
    const LeafyTree tree = leafy_tree(3);
    const Tadt tadt = build_tadt(tree.string);
    const TurtleResult drawn = interpret(tree.string, tree.turtle);
    ASSERT_EQ(drawn.leaves.size(), 6u * 27 + 2u * (27 + 9));  // the file's leaf count formula
    const FoliageHierarchy h = build_foliage_hierarchy(tadt, drawn.leaves);
    ASSERT_FALSE(h.empty());
    EXPECT_EQ(h.boxes[0].leaf_count(), drawn.leaves.size());
    for (std::size_t b = 0; b < h.boxes.size(); ++b) {
        const FoliageBox& box = h.boxes[b];
        for (std::size_t l = box.leaf_begin; l < box.leaf_end; ++l)
            for (const auto& p : leaf_outline(drawn.leaves[l]))
                ASSERT_TRUE(box.box.contains(p.cast<double>()) || box.box.exteriorDistance(p.cast<double>()) < 1e-6) << b;
        std::size_t in_children = box.own_leaves;
        for (int c : box.children) {
            EXPECT_TRUE(contains(box.box, h.boxes[static_cast<std::size_t>(c)].box));
            EXPECT_EQ(h.boxes[static_cast<std::size_t>(c)].parent, static_cast<int>(b));
            in_children += h.boxes[static_cast<std::size_t>(c)].leaf_count();
        }
        EXPECT_EQ(in_children, box.leaf_count()) << b;  // own leaves + sub-branches partition the box's leaves
        EXPECT_GT(box.volume_ratio, 0.0);
        EXPECT_LE(box.volume_ratio, 1.0 + 1e-12);
    }
    EXPECT_GE(h.max_depth(), 3);
}

TEST(Foliage, ThresholdSelectsTexturedBoxes) {
    const LeafyTree tree = leafy_tree(3);
    const Tadt tadt = build_tadt(tree.string);
    const TurtleResult drawn = interpret(tree.string, tree.turtle);
    std::size_t previous = std::numeric_limits<std::size_t>::max();
    for (double threshold : {0.0, 0.001, 0.01, 0.1, 0.5, 0.999}) {
        FoliageOptions options;
        options.texture_threshold = threshold;
        const FoliageHierarchy h = build_foliage_hierarchy(tadt, drawn.leaves, options);
        for (const FoliageBox& box : h.boxes) EXPECT_EQ(box.textured, box.volume_ratio > threshold);
        EXPECT_TRUE(h.boxes[0].textured);
        EXPECT_LE(h.textured_count(), previous);
        previous = h.textured_count();
        if (threshold == 0.0) {
            EXPECT_EQ(h.textured_count(), h.boxes.size());
        }
    }
    EXPECT_EQ(previous, 1u);  // only the root box at 0.999
    FoliageOptions bad;
    bad.texture_threshold = 1.0;
    EXPECT_THROW(build_foliage_hierarchy(tadt, drawn.leaves, bad), Error);
    // Leaves from a chain prefix are in chain order, not string order: rejected.
    const MultiresChain chain = build_multires_chain(tree.string);
    const TurtleResult chain_order = extract_lod(chain, chain.lod_count() - 1, tree.turtle);
    EXPECT_THROW(build_foliage_hierarchy(tadt, chain_order.leaves), Error);
}

TEST(Foliage, CombinedLodAccountsForEveryLeaf) {
    const LeafyTree tree = leafy_tree(3);
    const MultiresChain chain = build_multires_chain(tree.string);
    const TurtleResult drawn = interpret(tree.string, tree.turtle);
    for (double threshold : {0.0, 0.02}) {
        FoliageOptions options;
        options.texture_threshold = threshold;
        const FoliageHierarchy h = build_foliage_hierarchy(chain.tadt, drawn.leaves, options);
        for (std::size_t k = 0; k < chain.lod_count(); ++k) {
            const TurtleResult lod = extract_lod(chain, k, tree.turtle);
            const FoliageLod f = foliage_for_prefix(chain.tadt, h, visited_nodes(chain, chain.lod_end(k)));
            EXPECT_EQ(lod.leaves.size() + f.attached_leaves.size() + f.leaves_in_textures + f.leaves_in_small_boxes, drawn.leaves.size())
                    << k;
            if (threshold == 0.0) {
                EXPECT_TRUE(f.small_boxes.empty());
            }
            for (int b : f.textured_boxes) EXPECT_TRUE(h.boxes[static_cast<std::size_t>(b)].textured);
            for (int b : f.small_boxes) EXPECT_FALSE(h.boxes[static_cast<std::size_t>(b)].textured);
        }
        const FoliageLod last = foliage_for_prefix(chain.tadt, h, visited_nodes(chain, chain.entries.size()));
        EXPECT_TRUE(last.textured_boxes.empty());
        // Before the chain starts, the root box's textures stand for the whole crown.
        const FoliageLod none = foliage_for_prefix(chain.tadt, h, visited_nodes(chain, 0));
        EXPECT_EQ(none.textured_boxes, std::vector<int>{0});
        EXPECT_EQ(none.leaves_in_textures, drawn.leaves.size());
    }
}

TEST(Foliage, CutsCoverEveryLeafOnce) {
    const LeafyTree tree = leafy_tree(3);
    const Tadt tadt = build_tadt(tree.string);
    const TurtleResult drawn = interpret(tree.string, tree.turtle);
    FoliageOptions options;
    options.texture_threshold = 0.002;
    const FoliageHierarchy h = build_foliage_hierarchy(tadt, drawn.leaves, options);
    EXPECT_EQ(foliage_cut(h, 0), std::vector<int>{0});
    std::size_t previous = 1;
    for (int depth = 0; depth <= h.max_depth() + 1; ++depth) {
        const std::vector<int> cut = foliage_cut(h, depth);
        std::vector<int> covered(drawn.leaves.size(), 0);
        for (int b : cut) {
            const FoliageBox& box = h.boxes[static_cast<std::size_t>(b)];
            EXPECT_TRUE(box.textured);
            EXPECT_LE(box.depth, depth);
            for (std::size_t l = box.leaf_begin; l < box.leaf_end; ++l) ++covered[l];
        }
        EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; })) << depth;
        EXPECT_GE(cut.size(), previous);  // finer levels never have fewer boxes
        previous = cut.size();
    }
    EXPECT_GT(previous, 1u);
}

TEST(FoliageTextures, SixDiagonalPlanesOfABox) {
    const Eigen::Vector3d lo(0, 0, 0), hi(2, 3, 4);
    const auto planes = render::diagonal_planes(lo, hi);
    const std::vector<std::string> names{"z1", "z2", "y1", "y2", "x1", "x2"};
    auto is_vertex = [&](const Eigen::Vector3d& p) {
        for (int a = 0; a < 3; ++a)
            if (std::abs(p[a] - lo[a]) > 1e-12 && std::abs(p[a] - hi[a]) > 1e-12) return false;
        return true;
    };
    for (std::size_t k = 0; k < 6; ++k) {
        const auto& p = planes[k];
        EXPECT_EQ(p.name, names[k]);
        EXPECT_NEAR(p.u.dot(p.v), 0.0, 1e-12);
        EXPECT_GE(p.v.z(), 0.0);
        // The rectangle's four corners are box vertices, and it contains one box axis in full.
        const std::vector<Eigen::Vector3d> corners{p.corner, p.corner + p.u, p.corner + p.v, p.corner + p.u + p.v};
        for (const Eigen::Vector3d& c : corners) EXPECT_TRUE(is_vertex(c)) << p.name << " " << c.transpose();
    }
    // Planes containing z stand upright with v = the box's height.
    EXPECT_TRUE(planes[0].v.isApprox(Eigen::Vector3d(0, 0, 4)));
    EXPECT_TRUE(planes[0].u.isApprox(Eigen::Vector3d(2, 3, 0)));
    EXPECT_THROW(render::diagonal_planes(lo, Eigen::Vector3d(2, 0, 4)), Error);
}

TEST(FoliageTextures, LeafLandsOnItsTexel) {
    // A leaf at (0.5, 0.5, 0.8) in the unit box lies on the z1 plane (u = (1,1,0), v = z) at
    // s = 0.5, t = 0.8, i.e. pixel (64, 25) of a 128 x 128 texture.
    // The blade stands upright (heights 0.73 .. 0.88), facing the plane's normal (1,-1,0).
    LeafPlacement leaf;
    leaf.position = {0.5f, 0.5f, 0.73f};
    leaf.heading = {0, 0, 1};
    leaf.up = Eigen::Vector3f(1, -1, 0).normalized();
    leaf.size = 0.15f;
    const TriangleMesh mesh = foliage_mesh(std::vector<LeafPlacement>{leaf});
    const render::FoliageLayer layer{&mesh, {60, 130, 45, 255}};
    const auto textures = render::render_diagonal_textures(std::span(&layer, 1), {0, 0, 0}, {1, 1, 1}, 128);
    const render::Image& z1 = textures[0];
    ASSERT_EQ(z1.width, 128);
    ASSERT_EQ(z1.height, 128);
    EXPECT_EQ(z1.at(64, 25)[3], 255);               // the blade (heights 0.73 .. 0.88) covers t = 0.8
    EXPECT_GT(z1.at(64, 25)[1], z1.at(64, 25)[0]);  // green
    EXPECT_EQ(z1.at(64, 5)[3], 0);                  // above the tip: transparent
    EXPECT_EQ(z1.at(10, 25)[3], 0);                 // beside it: transparent
    std::size_t opaque = 0;
    for (int y = 0; y < 128; ++y)
        for (int x = 0; x < 128; ++x) opaque += z1.at(x, y)[3] == 255;
    // Blade area 0.15 * 0.075 * ~0.55 in a unit rectangle of width sqrt(2): a few dozen texels.
    EXPECT_GT(opaque, 30u);
    EXPECT_LT(opaque, 200u);
}

TEST(FoliageTextures, AtlasPlacesTilesRowMajor) {
    std::vector<render::Image> tiles;
    for (int i = 0; i < 7; ++i) tiles.emplace_back(4, 3, render::Rgba{static_cast<std::uint8_t>(i), 0, 0, 255});
    const render::Image atlas = render::pack_atlas(tiles, 3);
    EXPECT_EQ(atlas.width, 12);
    EXPECT_EQ(atlas.height, 9);
    for (int i = 0; i < 7; ++i) EXPECT_EQ(atlas.at((i % 3) * 4 + 1, (i / 3) * 3 + 2)[0], i) << i;
    EXPECT_EQ(atlas.at(11, 8)[3], 0);  // the unused slot stays transparent
}
