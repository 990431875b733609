#include "geometry/alpha_shape.hpp"
#include "lobes/patch_library.hpp"
#include "lobes/synthesis.hpp"
#include "lobes/texturing.hpp"

#include "config/species_profile.hpp"
#include "core/error.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace treelobes;
using namespace treelobes::lobes;
using treelobes::test::error_code_of;

namespace {

const SpeciesProfile& species(const std::string& name) {
    static const std::vector<SpeciesProfile> profiles = load_species_profiles(default_species_file());
    return find_species_profile(profiles, name);
}

// An axis-aligned closed box, outward.
TriangleMesh box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
    TriangleMesh m;
    for (int i = 0; i < 8; ++i) m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
    m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
               {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return m;
}

// A lobe tree: a 2 m trunk of two edges and one 2 x 2 x 1.5 m box lobe seeded at its top.
LobeTree boxed_tree() {
    LobeTree t;
    t.skeleton.add_node({0, 0, 0}, 0.08f, -1);
    t.skeleton.add_node({0, 0, 1}, 0.06f, 0);
    t.skeleton.add_node({0, 0, 2}, 0.03f, 1);
    Lobe lobe;
    lobe.mesh = box({-1, -1, 1.9f}, {1, 1, 3.4f});
    lobe.seed_node = 2;
    lobe.seed_direction = {0, 0, 1};
    t.lobes.push_back(lobe);
    return t;
}

// Share of the placed patches' segment ends that lie outside the lobe.
double share_outside(const LobeTexture& texture, const PatchLibrary& lib, const LobeVolume& volume) {
    std::size_t outside = 0, all = 0;
    for (const auto& inst : texture.instances)
        for (const auto& s : lib.patches[inst.patch].segments) {
            outside += volume.inside(inst.apply(s.b)) ? 0 : 1;
            ++all;
        }
    return static_cast<double>(outside) / static_cast<double>(std::max<std::size_t>(all, 1));
}

}  // namespace

TEST(PatchLibrary, BranchletsArePartitionedIntoPatchesWithDockingPoints) {
    PatchLibraryOptions o;
    const PatchLibrary lib = build_patch_library(species("lagerstroemia"), o);
    EXPECT_EQ(lib.branchlets, 24);
    ASSERT_GT(lib.patches.size(), 24u * 3);
    std::size_t docks = 0, terminal = 0, leaves = 0;
    for (const Patch& p : lib.patches) {
        ASSERT_FALSE(p.segments.empty());
        EXPECT_LT(p.segments.front().a.norm(), 1e-6f);  // root at the origin
        EXPECT_NEAR(p.root_direction.norm(), 1.0f, 1e-4f);
        EXPECT_GE(p.root_thickness, 0.6f * o.min_twig_thickness);
        EXPECT_LE(p.root_thickness, o.max_root_thickness + 1e-6f);
        for (const auto& d : p.docks) {
            EXPECT_LT(d.thickness, p.root_thickness);  // twigs are thinner than their parent
            EXPECT_GE(d.thickness, o.min_twig_thickness);
        }
        docks += p.docks.size();
        terminal += p.docks.empty() ? 1 : 0;
        leaves += p.leaves.size();
    }
    EXPECT_GT(docks, 0u);
    EXPECT_GT(terminal, 0u);  // the smallest patches end the texturing
    EXPECT_GT(leaves, 0u);
    // Deterministic for a seed, different for another seed or species.
    const PatchLibrary again = build_patch_library(species("lagerstroemia"), o);
    ASSERT_EQ(again.patches.size(), lib.patches.size());
    EXPECT_EQ(again.patches.back().segments.back().b, lib.patches.back().segments.back().b);
    o.seed = 2;
    EXPECT_NE(build_patch_library(species("lagerstroemia"), o).patches[0].segments.back().b, lib.patches[0].segments.back().b);
    EXPECT_EQ(build_patch_library(species("pine")).leaf_shape, LeafShape::Needle);
    o.branchlets = 0;
    EXPECT_EQ(error_code_of([&] { build_patch_library(species("pine"), o); }), ExitCode::Usage);
}

// Douglas-Peucker on the chain axes: fewer twig segments, every grown node (leaf base, docking
// point, segment end) within the tolerance of the simplified axis, same root and tip.
TEST(PatchLibrary, SimplifiedAxesStayWithinTheTolerance) {
    PatchLibraryOptions grown;
    grown.simplify_tolerance = 0;
    PatchLibraryOptions simplified;
    simplified.simplify_tolerance = 1.0;
    const PatchLibrary a = build_patch_library(species("ficus_virens"), grown);
    const PatchLibrary b = build_patch_library(species("ficus_virens"), simplified);
    ASSERT_EQ(a.patches.size(), b.patches.size());
    std::size_t before = 0, after = 0;
    for (std::size_t i = 0; i < a.patches.size(); ++i) {
        const Patch &p = a.patches[i], &q = b.patches[i];
        before += p.segments.size();
        after += q.segments.size();
        ASSERT_FALSE(q.segments.empty());
        EXPECT_EQ(q.segments.front().a, p.segments.front().a);
        EXPECT_EQ(q.segments.back().b, p.segments.back().b);
        EXPECT_EQ(q.segments.front().thickness_a, p.segments.front().thickness_a);
        ASSERT_EQ(q.docks.size(), p.docks.size());
        ASSERT_EQ(q.leaves.size(), p.leaves.size());
        auto distance_to_axis = [&](const Eigen::Vector3f& x) {
            float best = std::numeric_limits<float>::max();
            for (const auto& s : q.segments) {
                const Eigen::Vector3f d = s.b - s.a;
                const float t = std::clamp((x - s.a).dot(d) / std::max(d.squaredNorm(), 1e-12f), 0.0f, 1.0f);
                best = std::min(best, (x - s.a - t * d).norm());
            }
            return best;
        };
        const float tolerance = 1.0f * p.root_thickness + 1e-5f;
        for (const auto& s : p.segments) EXPECT_LE(distance_to_axis(s.b), tolerance);
        for (const auto& d : q.docks) EXPECT_LE(distance_to_axis(d.position), tolerance);
        for (std::size_t k = 0; k + 1 < q.segments.size(); ++k) EXPECT_EQ(q.segments[k].b, q.segments[k + 1].a);  // connected
    }
    EXPECT_LT(after, before / 2);  // a ficus chain of 12 segments bends little
    simplified.simplify_tolerance = -1;
    EXPECT_EQ(error_code_of([&] { build_patch_library(species("ficus_virens"), simplified); }), ExitCode::Usage);
}

TEST(LobeVolume, InsideTestMatchesABox) {
    const LobeVolume v(box({0, 0, 0}, {2, 1, 1}), 20);
    EXPECT_TRUE(v.inside({1, 0.5f, 0.5f}));
    EXPECT_TRUE(v.inside({0.1f, 0.1f, 0.9f}));
    EXPECT_FALSE(v.inside({1, 0.5f, 1.2f}));
    EXPECT_FALSE(v.inside({-0.2f, 0.5f, 0.5f}));
    // Cell size 0.1 m: the box holds 20 x 10 x 10 cells.
    EXPECT_NEAR(v.inside_cells(), 2000, 250);
}

TEST(Texturing, FillsALobeDeterministically) {
    const LobeTree tree = boxed_tree();
    const PatchLibrary lib = build_patch_library(species("lagerstroemia"));
    TexturingOptions o;
    o.fill_cell = 0.2;
    const DockingPoint seed{tree.seed_position(tree.lobes[0]), {0, 0, 1}, tree.seed_thickness(tree.lobes[0])};
    const LobeTexture t = texture_lobe(tree.lobes[0].mesh, seed, lib, o, 0);
    ASSERT_GT(t.instances.size(), 10u);
    EXPECT_GE(t.filled, o.fill_target);
    // Most twig geometry lies inside the lobe.
    EXPECT_LT(share_outside(t, lib, LobeVolume(tree.lobes[0].mesh, 40)), 0.3);
    const LobeTexture again = texture_lobe(tree.lobes[0].mesh, seed, lib, o, 0);
    ASSERT_EQ(again.instances.size(), t.instances.size());
    EXPECT_EQ(again.instances.back().translation, t.instances.back().translation);
}

TEST(Texturing, FillPrefersOccupiedCells) {
    // The box lobe's points sit in one 0.8 m corner (a quarter of its width, 1/40 of its volume):
    // with their occupancy the patches go there; without it they spread over the whole box.
    const LobeTree tree = boxed_tree();
    const PatchLibrary lib = build_patch_library(species("lagerstroemia"));
    TexturingOptions o;
    o.fill_cell = 0.1;
    o.max_fill_cells = 2000;
    o.max_patches_per_lobe = 400;
    std::vector<Eigen::Vector3f> pts;
    for (float x = 0.2f; x < 1.0f; x += 0.05f)
        for (float y = 0.2f; y < 1.0f; y += 0.05f)
            for (float z = 2.6f; z < 3.4f; z += 0.05f) pts.emplace_back(x, y, z);
    const Occupancy occupancy = occupancy_of(pts, 0.1f);
    const DockingPoint seed{tree.seed_position(tree.lobes[0]), {0, 0, 1}, tree.seed_thickness(tree.lobes[0])};
    const LobeTexture uniform = texture_lobe(tree.lobes[0].mesh, seed, lib, o, 0);
    const LobeTexture guided = texture_lobe(tree.lobes[0].mesh, seed, lib, o, 0, &occupancy);
    const Occupancy none;
    const LobeTexture empty_occupancy = texture_lobe(tree.lobes[0].mesh, seed, lib, o, 0, &none);
    ASSERT_EQ(empty_occupancy.instances.size(), uniform.instances.size());  // an empty occupancy changes nothing
    EXPECT_EQ(empty_occupancy.instances.back().translation, uniform.instances.back().translation);
    // Targets: the corner's 0.51 m^3 (plus the rim cells it touches) on 0.1 m cells against the
    // box's 6 m^3 on 0.144 m cells (2,000 cells).
    EXPECT_LT(guided.target_cells, uniform.target_cells / 3);
    EXPECT_GE(guided.filled, o.fill_target);
    // Share of twig points in occupied cells, and the median distance from the points to the
    // nearest twig point (points along the twig axes, at most the grown segment length apart).
    auto fit = [&](const LobeTexture& t) {
        std::vector<Eigen::Vector3f> ends;
        for (const auto& inst : t.instances) {
            const Patch& patch = lib.patches[inst.patch];
            for (const auto& s : patch.segments) {
                const int n = std::max(1, static_cast<int>(std::ceil((s.b - s.a).norm() / patch.step - 1e-3f)));
                for (int k = 1; k <= n; ++k) ends.push_back(inst.apply(s.a + (static_cast<float>(k) / n) * (s.b - s.a)));
            }
        }
        std::size_t in = 0;
        for (const auto& e : ends) in += occupancy.occupied(e) ? 1 : 0;
        std::vector<float> d;
        for (std::size_t i = 0; i < pts.size(); i += 7) {
            float best = 1e9f;
            for (const auto& e : ends) best = std::min(best, (e - pts[i]).norm());
            d.push_back(best);
        }
        std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
        return std::pair{static_cast<double>(in) / static_cast<double>(ends.size()), d[d.size() / 2]};
    };
    const auto [uniform_share, uniform_median] = fit(uniform);
    const auto [guided_share, guided_median] = fit(guided);
    EXPECT_GT(guided_share, 2 * uniform_share) << uniform_share << " -> " << guided_share;
    // The guided lobe stops at the fill target with about half the patches of the uniform one
    // (220 against 400): its points are still nearly twice as close to a twig.
    EXPECT_LT(guided_median, 0.6f * uniform_median) << uniform_median << " -> " << guided_median;
    const LobeTexture again = texture_lobe(tree.lobes[0].mesh, seed, lib, o, 0, &occupancy);
    ASSERT_EQ(again.instances.size(), guided.instances.size());
    EXPECT_EQ(again.instances.back().translation, guided.instances.back().translation);
}

TEST(Synthesis, LodKeepsThickestEdgesAndLeafArea) {
    const LobeTree tree = boxed_tree();
    SynthesisOptions o;
    o.texturing.fill_cell = 0.2;
    const TexturedTree textured = texture_tree(tree, species("lagerstroemia"), o);
    const SynthesizedMesh full = synthesized_mesh(tree, textured, 1.0, o);
    const SynthesizedMesh half = synthesized_mesh(tree, textured, 0.5, o);
    EXPECT_EQ(full.skeleton_edges, 2u);
    EXPECT_EQ(half.skeleton_edges, 1u);
    EXPECT_GT(full.triangles(), half.triangles());
    EXPECT_LT(half.twig_segments, full.twig_segments);
    EXPECT_GE(half.twig_segments, full.twig_segments / 2);
    EXPECT_LT(half.leaf_count, full.leaf_count);
    EXPECT_GE(half.leaf_count, full.leaf_count / 2);
    // Stochastic pruning enlarges the kept leaves: the leaf area stays about the same.
    EXPECT_NEAR(half.leaves.area(), full.leaves.area(), 0.15 * full.leaves.area());
    EXPECT_EQ(full.leaves.faces.size(), 2 * full.leaf_count);
    EXPECT_EQ(error_code_of([&] { synthesized_mesh(tree, textured, 0.0, o); }), ExitCode::Usage);
    EXPECT_EQ(error_code_of([&] { synthesized_mesh(tree, textured, 1.5, o); }), ExitCode::Usage);
}

namespace {

// Lengths of a broad-leaved mesh's blades (add_leaf: base, side, tip, side).
// The occupancy of points filling boxed_tree()'s lobe in slabs across x, `slab` metres wide,
// the last of every `period` slabs empty (the gaps between fronds, or between a crown's tiers).
Occupancy slabs_across_the_box(float slab, int period, float cell) {
    std::vector<Eigen::Vector3f> pts;
    for (float x = -0.9875f; x < 1.0f; x += 0.05f)  // off the slabs' faces
        for (float y = -0.9875f; y < 1.0f; y += 0.05f)
            for (float z = 1.9125f; z < 3.4f; z += 0.05f)
                if (static_cast<int>(std::floor((x + 1.0f) / slab)) % period != period - 1) pts.emplace_back(x, y, z);
    return occupancy_of(pts, cell);
}

// Whether the blade whose vertices begin at `first` (add_leaf: base, ..., tip, ...) ends in an
// occupied cell, up to the final sizing of the leaves to the stored area: a factor within 1 % of
// 1 that takes up the rounding of the leaf counts, and can move a tip that ended just across a
// cell's face (as a turn often leaves it) back across it by a fraction of a millimetre.
bool tip_seen(const TriangleMesh& leaves, std::size_t first, const Occupancy& seen) {
    const Eigen::Vector3f &base = leaves.vertices[first], &tip = leaves.vertices[first + 2];
    return seen.occupied(tip) || seen.occupied(base + 1.01f * (tip - base)) || seen.occupied(base + 0.99f * (tip - base));
}

std::vector<float> blade_lengths(const TriangleMesh& leaves) {
    std::vector<float> lengths;
    for (std::size_t i = 0; i + 3 < leaves.vertices.size(); i += 4) lengths.push_back((leaves.vertices[i + 2] - leaves.vertices[i]).norm());
    return lengths;
}

}  // namespace

// A stored leaf area (a rebuilt model's original) is given exactly, at every level of detail.
// Below the area of the leaves the patches offer at the species' size, the blades keep that size
// and fewer are drawn: shrunk instead, a palm's 0.6 m leaflets were drawn 0.16-0.18 m long and its
// crown's rim thinned out (docs/rebuild.md). Above it, every offered blade is drawn, enlarged
// about its base. The twigs stay as they are.
TEST(Synthesis, StoredLeafAreaThinsOrEnlargesTheBlades) {
    LobeTree tree = boxed_tree();
    SynthesisOptions o;
    o.texturing.fill_cell = 0.2;
    const TexturedTree textured = texture_tree(tree, species("lagerstroemia"), o);
    ASSERT_EQ(textured.library.leaf_shape, LeafShape::Broad);
    TexturedTree whole = textured;  // every leaf of the placed patches at the species' size
    whole.leaf_share = 1;
    const SynthesizedMesh offered = synthesized_mesh(tree, whole, 1.0, o);
    const SynthesizedMesh natural = synthesized_mesh(tree, textured, 1.0, o);
    ASSERT_GT(offered.leaves.area(), 0);
    const auto [shortest, longest] = std::ranges::minmax(blade_lengths(offered.leaves));
    for (const double factor : {0.05, 0.2}) {
        tree.leaf_area_m2 = factor * textured.leaf_share * offered.leaves.area();
        for (const double lod : {1.0, 0.5}) {
            const SynthesizedMesh sized = synthesized_mesh(tree, textured, lod, o);
            EXPECT_NEAR(sized.leaves.area(), tree.leaf_area_m2, 1e-3 * tree.leaf_area_m2) << factor << " at LOD " << lod;
            EXPECT_EQ(sized.wood.faces.size(), synthesized_mesh(boxed_tree(), textured, lod, o).wood.faces.size());
        }
        const SynthesizedMesh sized = synthesized_mesh(tree, textured, 1.0, o);
        EXPECT_NEAR(static_cast<double>(sized.leaf_count), factor * static_cast<double>(natural.leaf_count), 0.1 * factor * natural.leaf_count);
        for (const float length : blade_lengths(sized.leaves)) {  // the species' blades, within the last count's rounding
            EXPECT_GE(length, 0.98f * shortest) << factor;
            EXPECT_LE(length, 1.02f * longest) << factor;
        }
    }
    tree.leaf_area_m2 = 3.0 * natural.leaves.area();
    const SynthesizedMesh enlarged = synthesized_mesh(tree, textured, 1.0, o);
    EXPECT_NEAR(enlarged.leaves.area(), tree.leaf_area_m2, 1e-3 * tree.leaf_area_m2);
    ASSERT_EQ(enlarged.leaves.vertices.size(), natural.leaves.vertices.size());
    for (std::size_t i = 0; i < enlarged.leaves.vertices.size(); i += 4)  // broad leaves: the base is a blade's first vertex
        EXPECT_EQ(enlarged.leaves.vertices[i], natural.leaves.vertices[i]);
}

// A rebuilt tree (one that stores its leaf area) draws leaves and twigs only where its lobe's
// occupancy saw the crown: every leaf tip and every twig's middle in an occupied cell. The same
// lobe synthesized from a scan (no stored area) draws its patches whole.
TEST(Synthesis, ARebuiltTreeDrawsLeavesAndTwigsOnlyInItsOccupiedCells) {
    LobeTree tree = boxed_tree();
    std::vector<Eigen::Vector3f> pts;
    for (float x = 0.2f; x < 1.0f; x += 0.05f)
        for (float y = -1.0f; y < 1.0f; y += 0.05f)
            for (float z = 2.0f; z < 3.4f; z += 0.05f) pts.emplace_back(x, y, z);
    tree.lobes[0].occupancy = occupancy_of(pts, 0.2f);
    const Occupancy& seen = tree.lobes[0].occupancy;
    SynthesisOptions o;
    o.texturing.fill_cell = 0.1;
    const TexturedTree textured = texture_tree(tree, species("lagerstroemia"), o);
    const auto tips_seen = [&](const SynthesizedMesh& mesh) {
        std::size_t in = 0;
        for (std::size_t i = 0; i + 3 < mesh.leaves.vertices.size(); i += 4) in += tip_seen(mesh.leaves, i, seen) ? 1 : 0;
        return std::pair{in, mesh.leaf_count};
    };
    std::size_t twigs_seen = 0;
    for (const auto& inst : textured.lobes[0].instances)
        for (const auto& s : textured.library.patches[inst.patch].segments) twigs_seen += seen.occupied(inst.apply(0.5f * (s.a + s.b))) ? 1 : 0;
    const SynthesizedMesh scanned = synthesized_mesh(tree, textured, 1.0, o);
    const auto [scanned_in, scanned_all] = tips_seen(scanned);
    EXPECT_LT(scanned_in, scanned_all * 9 / 10);  // the patches reach out of the occupied cells
    EXPECT_GT(scanned.twig_segments, twigs_seen);
    tree.leaf_area_m2 = 0.2 * scanned.leaves.area();
    const SynthesizedMesh rebuilt = synthesized_mesh(tree, textured, 1.0, o);
    const auto [rebuilt_in, rebuilt_all] = tips_seen(rebuilt);
    ASSERT_GT(rebuilt_all, 0u);
    EXPECT_EQ(rebuilt_in, rebuilt_all);
    EXPECT_EQ(rebuilt.twig_segments, twigs_seen);
    EXPECT_NEAR(rebuilt.leaves.area(), tree.leaf_area_m2, 1e-3 * tree.leaf_area_m2);
}

// A rebuilt tree's leaf pointing out of the seen cells is turned about its base into them, not
// dropped: the stored area is then drawn at the species' size where the leaves seen as placed
// would have had to be enlarged (by the square root of 1.5 here), and every tip stays in a seen
// cell. The occupancy: 10 cm cells in slabs one cell thick, one cell apart, across the lobe.
TEST(Synthesis, LeavesPointingOutOfTheSeenCellsAreTurnedIntoThem) {
    LobeTree tree = boxed_tree();
    tree.lobes[0].occupancy = slabs_across_the_box(0.1f, 2, 0.1f);
    const Occupancy& seen = tree.lobes[0].occupancy;
    SynthesisOptions o;
    o.texturing.fill_cell = 0.1;
    o.library.simplify_tolerance = 0;  // every leaf of the patches offered (no thinning to the twig triangles)
    const TexturedTree textured = texture_tree(tree, species("lagerstroemia"), o);
    ASSERT_DOUBLE_EQ(textured.leaf_share, 1.0);
    const SynthesizedMesh scanned = synthesized_mesh(tree, textured, 1.0, o);  // every leaf as placed, at the species' size
    const auto [shortest, longest] = std::ranges::minmax(blade_lengths(scanned.leaves));
    double seen_as_placed = 0;
    std::size_t seen_count = 0;
    for (std::size_t i = 0; i + 3 < scanned.leaves.vertices.size(); i += 4)
        if (seen.occupied(scanned.leaves.vertices[i + 2])) {
            for (const std::size_t f : {i / 2, i / 2 + 1}) {  // a blade's two triangles
                const auto& [a, b, c] = scanned.leaves.faces[f];
                const auto& v = scanned.leaves.vertices;
                seen_as_placed += 0.5 * static_cast<double>((v[b] - v[a]).cross(v[c] - v[a]).norm());
            }
            ++seen_count;
        }
    tree.leaf_area_m2 = 1e6;  // more than any leaves hold: every leaf that can be drawn is
    EXPECT_GT(synthesized_mesh(tree, textured, 1.0, o).leaf_count, seen_count * 3 / 2);
    tree.leaf_area_m2 = 1.5 * seen_as_placed;
    const SynthesizedMesh rebuilt = synthesized_mesh(tree, textured, 1.0, o);
    EXPECT_NEAR(rebuilt.leaves.area(), tree.leaf_area_m2, 1e-3 * tree.leaf_area_m2);
    for (const float length : blade_lengths(rebuilt.leaves)) {
        EXPECT_GE(length, 0.98f * shortest);
        EXPECT_LE(length, 1.02f * longest);
    }
    std::size_t tips_seen = 0;
    for (std::size_t i = 0; i + 3 < rebuilt.leaves.vertices.size(); i += 4) tips_seen += tip_seen(rebuilt.leaves, i, seen) ? 1 : 0;
    EXPECT_EQ(tips_seen, rebuilt.leaf_count);
}

// The leaves drawn, and how many of them have their tip, a point a cell apart from it back
// towards the base or the base itself in an empty cell.
struct BladeCheck {
    std::size_t drawn = 0, crossing_empty_cells = 0;
};
BladeCheck check_blades(const SynthesizedMesh& mesh, const Occupancy& seen) {
    BladeCheck c;
    for (std::size_t i = 0; i + 3 < mesh.leaves.vertices.size(); i += 4) {  // add_leaf: base, ..., tip, ...
        const Eigen::Vector3f base = mesh.leaves.vertices[i], tip = mesh.leaves.vertices[i + 2];
        const Eigen::Vector3f toward_base = (base - tip).normalized();
        bool crossing = !seen.occupied(base);
        for (float back = 0; back < (tip - base).norm(); back += seen.cell) crossing = crossing || !seen.occupied(tip + toward_base * back);
        ++c.drawn;
        c.crossing_empty_cells += crossing ? 1 : 0;
    }
    return c;
}

// Blades two or more cells long (the palm's 0.6 m leaflets on 20 cm cells) are drawn only where
// the occupancy holds them from the tip back to the base; shorter ones (lagerstroemia's 7 cm) by
// their tip alone. The occupancy: 40 cm slabs of occupied cells 20 cm apart, the gaps between
// fronds.
TEST(Synthesis, LongBladesAreDrawnOnlyAcrossOccupiedCells) {
    LobeTree tree = boxed_tree();
    tree.lobes[0].occupancy = slabs_across_the_box(0.2f, 3, 0.2f);
    const Occupancy& seen = tree.lobes[0].occupancy;
    SynthesisOptions o;
    o.texturing.fill_cell = 0.1;
    for (const char* name : {"palm", "lagerstroemia"}) {
        LobeTree t = tree;
        const TexturedTree textured = texture_tree(t, species(name), o);
        const SynthesizedMesh scanned = synthesized_mesh(t, textured, 1.0, o);  // no stored area: every leaf
        EXPECT_GT(check_blades(scanned, seen).crossing_empty_cells, 0u) << name;
        t.leaf_area_m2 = 0.01 * scanned.leaves.area();  // small enough that no drawn leaf is enlarged
        const BladeCheck rebuilt = check_blades(synthesized_mesh(t, textured, 1.0, o), seen);
        ASSERT_GT(rebuilt.drawn, 0u) << name;
        if (std::string(name) == "palm")
            EXPECT_EQ(rebuilt.crossing_empty_cells, 0u);
        else
            EXPECT_GT(rebuilt.crossing_empty_cells, 0u) << "short blades are judged by their tip";
    }
}

TEST(Synthesis, LeafyPatchesAreThinnedToTheTriangleBudget) {
    const LobeTree tree = boxed_tree();
    SynthesisOptions o;
    o.max_triangles = 150000;
    // Lagerstroemia patches with their grown (unsimplified) axes carry fewer leaf than twig
    // triangles: no thinning. Simplified, their twigs are cheaper than their leaves: thinning.
    SynthesisOptions grown = o;
    grown.library.simplify_tolerance = 0;
    EXPECT_DOUBLE_EQ(texture_tree(tree, species("lagerstroemia"), grown).leaf_share, 1.0);
    EXPECT_LT(texture_tree(tree, species("lagerstroemia"), o).leaf_share, 1.0);
    // Mahogany's compound leaves outweigh its twigs: leaves are thinned and the budget holds.
    const TexturedTree textured = texture_tree(tree, species("mahogany"), o);
    EXPECT_LT(textured.leaf_share, 1.0);
    EXPECT_GT(textured.leaf_share, 0.0);
    const SynthesizedMesh mesh = synthesized_mesh(tree, textured, 1.0, o);
    EXPECT_LE(mesh.triangles(), o.max_triangles);
    double full_leaf_triangles = 0;
    for (const auto& lobe : textured.lobes)
        for (const auto& inst : lobe.instances)
            full_leaf_triangles += 2.0 * static_cast<double>(textured.library.patches[inst.patch].leaves.size());
    EXPECT_LT(static_cast<double>(mesh.leaves.faces.size()), 0.9 * full_leaf_triangles);  // thinned
    // The kept leaves are enlarged: the leaf area stays about that of the unthinned patches.
    TexturedTree unthinned = textured;
    unthinned.leaf_share = 1;
    const double full_area = synthesized_mesh(tree, unthinned, 1.0, o).leaves.area();
    EXPECT_NEAR(mesh.leaves.area(), full_area, 0.15 * full_area);
}

TEST(Synthesis, TriangleBudgetIsAHardBound) {
    // The budget counts the triangles of every placed patch (and the main skeleton's), so the
    // mesh never exceeds it - also for species whose fitted patches are larger than the library's
    // mean (palm overshot a budget converted to a patch count by 20 %) - and a lobe that stops
    // for the budget has spent all of it but less than the smallest patch.
    const LobeTree tree = boxed_tree();
    int spent = 0, runs = 0;
    for (const std::string name : {"palm", "mahogany", "lagerstroemia", "pine"})
        for (const std::size_t budget : {20000u, 60000u, 150000u}) {
            SynthesisOptions o;
            o.max_triangles = budget;
            o.texturing.fill_target = 1.0;  // the whole box, so the budget is what stops
            const TexturedTree textured = texture_tree(tree, species(name), o);
            const SynthesizedMesh mesh = synthesized_mesh(tree, textured, 1.0, o);
            ASSERT_EQ(textured.lobes.size(), 1u);
            const LobeTexture& lobe = textured.lobes[0];
            EXPECT_LE(mesh.triangles(), budget) << name;
            // The texture's count is the drawn one: skeleton cylinders plus the patches.
            std::size_t counted = 0, smallest = SIZE_MAX;
            for (const auto& inst : lobe.instances)
                counted += patch_triangles(textured.library.patches[inst.patch], o.twig_sides, textured.leaf_share);
            for (const auto& p : textured.library.patches)
                smallest = std::min(smallest, patch_triangles(p, o.twig_sides, textured.leaf_share));
            EXPECT_EQ(lobe.triangles, counted);
            EXPECT_EQ(mesh.triangles(), lobe.triangles + (o.max_triangles - textured.patch_budget)) << name;
            if (lobe.budget_spent) {
                EXPECT_LT(textured.patch_budget - lobe.triangles, smallest) << name << " " << budget;
            }
            spent += lobe.budget_spent ? 1 : 0;
            ++runs;
        }
    EXPECT_GE(spent, 3) << runs;  // the bound was binding (palm fills the box below every budget)
}

// A tall, narrow lobe (a conifer's crown: 1 x 1 x 8 m) on a budget that fills a quarter of it.
// Growing only from the seed at its foot, the patches stay in its lower part; with re-seeds
// interleaved into the queue (the default) they reach its top quarter too.
TEST(Texturing, ReseedsSpreadATightBudgetOverATallLobe) {
    const PatchLibrary lib = build_patch_library(species("pine"));
    const TriangleMesh tall = box({-0.5f, -0.5f, 2}, {0.5f, 0.5f, 10});
    const DockingPoint seed{{0, 0, 2}, {0, 0, 1}, 0.03f};
    const auto top_quarter_share = [&](int reseed_every) {
        TexturingOptions o;
        o.fill_cell = 0.1;
        o.reseed_every = reseed_every;
        o.max_triangles = 20000;
        const LobeTexture t = texture_lobe(tall, seed, lib, o, 0);
        EXPECT_TRUE(t.budget_spent) << reseed_every;
        std::size_t top = 0, all = 0;
        for (const auto& inst : t.instances)
            for (const auto& s : lib.patches[inst.patch].segments) {
                top += inst.apply(s.b).z() > 8 ? 1 : 0;
                ++all;
            }
        return static_cast<double>(top) / static_cast<double>(std::max<std::size_t>(all, 1));
    };
    const double from_seed_only = top_quarter_share(0), spread = top_quarter_share(TexturingOptions{}.reseed_every);
    EXPECT_LT(from_seed_only, 0.02) << spread;
    EXPECT_GT(spread, 0.05) << from_seed_only;
}

// A patch whose geometry would mostly stick out of the lobe is not placed (Livny et al. 2011,
// Sec. 5: the fit is measured against the lobe): in a thin lobe, long patches at its rim were
// placed anyway when they were the best of a poor choice.
TEST(Texturing, PatchesThatStickOutOfTheLobeAreNotPlaced) {
    const PatchLibrary lib = build_patch_library(species("pine"));
    const TriangleMesh thin = box({-0.3f, -0.3f, 2}, {0.3f, 0.3f, 4});
    const DockingPoint seed{{0, 0, 2}, {0, 0, 1}, 0.03f};
    const LobeVolume volume(thin, 40);
    const auto outside_share = [&](double min_inside_share) {
        TexturingOptions o;
        o.fill_cell = 0.15;
        o.min_inside_share = min_inside_share;
        const LobeTexture t = texture_lobe(thin, seed, lib, o, 0);
        return share_outside(t, lib, volume);
    };
    const double anyway = outside_share(0), fitted = outside_share(TexturingOptions{}.min_inside_share);
    EXPECT_LT(fitted, 0.5 * anyway) << fitted << " " << anyway;
    EXPECT_GT(fitted, 0.0) << "seeds and re-seeds keep their patch";
    for (const double bad : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
        TexturingOptions o;
        o.min_inside_share = bad;
        EXPECT_EQ(error_code_of([&] { texture_lobe(thin, seed, lib, o, 0); }), ExitCode::Usage) << bad;
    }
}

// Palm and willow patches are long: a re-seed sized to reach an empty cell of a thin lobe from
// a twig far from it grew a patch that stuck out of the lobe (14 % and 8 % of all patch geometry
// outside measured before re-seeds were made thinner, 7.8 % and 5.0 % after).
TEST(Texturing, ReseedsAreMadeThinnerToFitAThinLobe) {
    const TriangleMesh thin = box({-0.3f, -0.3f, 2}, {0.3f, 0.3f, 6});
    const LobeVolume volume(thin, 40);
    const DockingPoint seed{{0, 0, 2}, {0, 0, 1}, 0.03f};
    TexturingOptions o;
    o.fill_cell = 0.1;
    for (const auto& [name, most_outside] : {std::pair{"palm", 0.11}, std::pair{"willow", 0.065}}) {
        const PatchLibrary lib = build_patch_library(species(name));
        const LobeTexture t = texture_lobe(thin, seed, lib, o, 0);
        EXPECT_GT(t.reseeds, 50u) << name;
        EXPECT_LT(share_outside(t, lib, volume), most_outside) << name;
    }
}

// Lobes that know their leaf share (a rebuilt mesh's wood/leaf labels): a bare lobe draws no
// leaves, the leafy one draws the leaves the bare one gave up, and the tree keeps at most its
// number of leaves (the triangle budget holds); unknown shares draw as before.
TEST(Synthesis, LobeLeafSharesMoveLeavesToTheLeafyLobes) {
    LobeTree tree = boxed_tree();  // lobe 0: x in -1..1, seeded at (0, 0, 2)
    tree.skeleton.add_node({2.5f, 0, 2}, 0.03f, 1);
    Lobe second = tree.lobes[0];  // lobe 1: x in 1.5..3.5, seeded at (2.5, 0, 2)
    second.mesh = box({1.5f, -1, 1.9f}, {3.5f, 1, 3.4f});
    second.seed_node = 3;
    tree.lobes.push_back(second);
    SynthesisOptions o;
    o.texturing.fill_cell = 0.2;
    o.max_triangles = 100000;
    const TexturedTree textured = texture_tree(tree, species("mahogany"), o);
    ASSERT_LT(textured.leaf_share, 0.5);  // thinned leaves: room to draw more in a leafy lobe
    const auto leaves_between = [](const SynthesizedMesh& mesh, float lo, float hi) {
        std::size_t n = 0;
        for (std::size_t i = 0; i < mesh.leaves.vertices.size(); i += 4) {  // a broad blade's first vertex is its base
            const float x = mesh.leaves.vertices[i].x();
            n += x >= lo && x < hi ? 1 : 0;
        }
        return n;
    };
    const SynthesizedMesh unknown = synthesized_mesh(tree, textured, 1.0, o);
    tree.lobes[0].leaf_share = 0.0f;
    tree.lobes[1].leaf_share = 0.9f;
    const SynthesizedMesh shared = synthesized_mesh(tree, textured, 1.0, o);
    EXPECT_GT(leaves_between(unknown, -10, 0), 100u);
    EXPECT_EQ(leaves_between(shared, -10, 0), 0u);  // lobe 0's left half: bare
    EXPECT_GT(leaves_between(shared, 1.25f, 10), leaves_between(unknown, 1.25f, 10) * 3 / 2);
    EXPECT_LE(shared.leaf_count, unknown.leaf_count);
    EXPECT_GT(shared.leaf_count, unknown.leaf_count * 8 / 10);
    EXPECT_LE(shared.triangles(), o.max_triangles);
    EXPECT_EQ(shared.wood.faces.size(), unknown.wood.faces.size());
}

// A lobe's seed takes the skeleton's diameter at p_i: a palm's crown lobe seeded on its trunk top
// grew a seed patch standing 2 m above the fronds. The seed is refitted thinner like a re-seed.
TEST(Texturing, AThickSeedIsMadeThinnerToFitItsLobe) {
    const PatchLibrary lib = build_patch_library(species("palm"));
    const TriangleMesh crown = box({-1.5f, -1.5f, 6}, {1.5f, 1.5f, 7.5f});
    const DockingPoint trunk_top{{0, 0, 6}, {0, 0, 1}, 0.3f};
    TexturingOptions o;
    o.max_patches_per_lobe = 1;  // the seed's patch alone
    const LobeTexture t = texture_lobe(crown, trunk_top, lib, o, 0);
    ASSERT_EQ(t.instances.size(), 1u);
    // At the seed's thickness 75 % of the patch lay outside the crown, scaled to the largest
    // stretch (2); refitted thinner, none of it.
    EXPECT_LT(share_outside(t, lib, LobeVolume(crown, 40)), 1.0 - TexturingOptions{}.min_inside_share);
    EXPECT_LT(t.instances[0].scale, 1.5f);
}
