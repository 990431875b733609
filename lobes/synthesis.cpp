#include "lobes/synthesis.hpp"

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/tree_graph.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>

namespace treelobes::lobes {

namespace {

constexpr float kMinTwigRadius = 0.0008f;  // metres: thinner twigs are drawn this thick
constexpr double kMinPatchesPerLobe = 20;
constexpr double kCellsPerPatch = 2;
constexpr double kMinLeafShare = 0.1;  // leaves are thinned at most to this fraction

// An open prism of `sides` faces around segment a-b (twigs are too thin for caps to show).
void add_prism(TriangleMesh& mesh, const Eigen::Vector3f& a, const Eigen::Vector3f& b, float ra, float rb, int sides) {
    const Eigen::Vector3f axis = b - a;
    if (axis.norm() < 1e-6f) return;
    const Eigen::Vector3f t = axis.normalized();
    const Eigen::Vector3f u = t.unitOrthogonal(), v = t.cross(u);
    const int base = static_cast<int>(mesh.vertices.size());
    for (int k = 0; k < sides; ++k) {
        const float angle = 2.0f * std::numbers::pi_v<float> * k / sides;
        const Eigen::Vector3f n = std::cos(angle) * u + std::sin(angle) * v;
        mesh.vertices.push_back(a + ra * n);
        mesh.vertices.push_back(b + rb * n);
    }
    for (int k = 0; k < sides; ++k) {
        const int k1 = (k + 1) % sides;
        const int a0 = base + 2 * k, b0 = a0 + 1, a1 = base + 2 * k1, b1 = a1 + 1;
        mesh.faces.push_back({a0, a1, b1});  // counter-clockwise seen from outside
        mesh.faces.push_back({a0, b1, b0});
    }
}

// A leaf blade: a rhombus (broad leaves, leaflets) or a thin strip (needles), two triangles.
void add_leaf(TriangleMesh& mesh, const Eigen::Vector3f& base, const Eigen::Vector3f& direction, const Eigen::Vector3f& normal,
              float length, float width, LeafShape shape) {
    const Eigen::Vector3f side = normal.cross(direction).normalized() * (0.5f * width);
    const int i = static_cast<int>(mesh.vertices.size());
    const Eigen::Vector3f tip = base + length * direction;
    if (shape == LeafShape::Needle) {
        mesh.vertices.insert(mesh.vertices.end(), {base - side, base + side, tip + side, tip - side});
    } else {
        const Eigen::Vector3f mid = base + 0.45f * length * direction;
        mesh.vertices.insert(mesh.vertices.end(), {base, mid + side, tip, mid - side});
    }
    mesh.faces.push_back({i, i + 1, i + 2});
    mesh.faces.push_back({i, i + 2, i + 3});
}

// Sizes every leaf blade (the four vertices of add_leaf) about its base so that the blades'
// area is `target`. After plan_leaf_area the factor is close to 1: it only takes up the rounding
// of the leaf counts.
void scale_leaves_to_area(TriangleMesh& leaves, double target, LeafShape shape) {
    const double area = leaves.area();
    if (!(area > 0)) return;
    const auto s = static_cast<float>(std::sqrt(target / area));
    for (std::size_t i = 0; i + 3 < leaves.vertices.size(); i += 4) {
        Eigen::Vector3f* blade = &leaves.vertices[i];
        const Eigen::Vector3f base = shape == LeafShape::Needle ? Eigen::Vector3f(0.5f * (blade[0] + blade[1])) : blade[0];
        for (int k = 0; k < 4; ++k) blade[k] = base + s * (blade[k] - base);
    }
}

// Per lobe, a factor on the number of leaves drawn, when the lobes know their leaf share
// (lobe_tree.hpp): the share over the tree's mean share (weighted by the patch leaves each lobe
// holds), so the tree keeps its number of leaves (and of triangles) while the leaves move from
// the lobes the input saw as bare twigs to the leafy ones. Empty when no lobe knows its share.
std::vector<double> lobe_leaf_weights(const LobeTree& tree, const TexturedTree& textured) {
    std::vector<double> leaves(tree.lobes.size(), 0.0);
    double known_leaves = 0, known_share = 0;
    for (std::size_t l = 0; l < tree.lobes.size(); ++l) {
        for (const auto& inst : textured.lobes[l].instances)
            leaves[l] += static_cast<double>(textured.library.patches[inst.patch].leaves.size());
        if (tree.lobes[l].leaf_share < 0) continue;
        known_leaves += leaves[l];
        known_share += leaves[l] * tree.lobes[l].leaf_share;
    }
    if (!(known_leaves > 0)) return {};
    const double mean_share = known_share / known_leaves;
    std::vector<double> weight(tree.lobes.size(), 1.0);
    for (std::size_t l = 0; l < tree.lobes.size(); ++l)
        if (tree.lobes[l].leaf_share >= 0) weight[l] = mean_share > 0 ? tree.lobes[l].leaf_share / mean_share : 0.0;
    return weight;
}

// Leaves of a placed patch at a share of them (the budget thinning's, times the level of
// detail's fraction): rounded up, as the triangle budget counted them, or with lobe weights that
// share times the lobe's weight, rounded down, so the tree never draws more than the budget
// counted.
std::size_t offered_leaves(const Patch& patch, double leaf_share, const std::vector<double>& leaf_weight, std::size_t lobe) {
    if (leaf_weight.empty()) return kept_leaves(leaf_share, patch.leaves.size());
    return std::min(patch.leaves.size(),
                    static_cast<std::size_t>(std::floor(leaf_share * leaf_weight[lobe] * static_cast<double>(patch.leaves.size()))));
}

float blade_area(const PatchLeaf& leaf, LeafShape shape) {
    return shape == LeafShape::Needle ? leaf.length * leaf.width : 0.5f * leaf.length * leaf.width;
}

// Points a blade is checked at, at most: a damaged file's tiny cells cost no more than this.
constexpr float kMaxBladeChecks = 64;

// A leaf of a rebuilt tree is drawn only where the scan saw its lobe (every leaf of a lobe
// without occupancy): its tip in an occupied cell and, for a blade at least two cells long,
// also every point a cell apart from the tip back to its base, and the base. Such a blade (the
// palm's 0.6 m leaflets on 20-30 cm cells) crosses cells whose emptiness is a real gap, between
// two fronds; a shorter blade's other cell is its tip's neighbour, empty more often for want of
// samples (terminalia's 0.2 m leaves on 14 cm cells, checked so, lost the crown's rim;
// docs/rebuild.md).
bool leaf_seen(const Lobe& lobe, const PatchInstance& inst, const PatchLeaf& leaf) {
    const Occupancy& seen = lobe.occupancy;
    if (seen.empty()) return true;
    const Eigen::Vector3f toward_tip = inst.rotation * leaf.direction, tip = inst.apply(leaf.base) + toward_tip * leaf.length;
    if (!seen.occupied(tip)) return false;
    if (leaf.length < 2 * seen.cell) return true;
    // Counted steps: a float sum of a tiny cell would stop growing before it reached the base.
    const float step = std::max(seen.cell, leaf.length / kMaxBladeChecks);
    const auto steps = static_cast<int>(std::ceil(leaf.length / step));
    for (int j = 1; j < steps; ++j)
        if (!seen.occupied(tip - toward_tip * (static_cast<float>(j) * step))) return false;
    return seen.occupied(tip - toward_tip * leaf.length);
}

// The turns tried, smallest first, for a leaf whose tip the scan did not see: about its base, in
// its blade's plane, as a leaf turns on its stalk.
constexpr std::array<float, 7> kLeafTurns{std::numbers::pi_v<float> / 4,     -std::numbers::pi_v<float> / 4,
                                          std::numbers::pi_v<float> / 2,     -std::numbers::pi_v<float> / 2,
                                          3 * std::numbers::pi_v<float> / 4, -3 * std::numbers::pi_v<float> / 4,
                                          std::numbers::pi_v<float>};

// A leaf of a rebuilt tree as it is drawn: as placed where the scan saw it (leaf_seen), else
// turned by the smallest of kLeafTurns that brings it into seen cells, else not at all. The
// texturing fits the patches to the lobe's hull, so many leaves point out of the cells where the
// scan saw foliage. Dropped, they left the seen leaves to carry the stored area: on terminalia's
// first tree those held 417 of its 1,002 m² and were drawn 1.55 times larger, into the gaps
// between the crown's tiers; turned, 946 m² are seen at the species' size (docs/rebuild.md).
std::optional<PatchLeaf> drawn_leaf(const Lobe& lobe, const PatchInstance& inst, const PatchLeaf& leaf) {
    if (leaf_seen(lobe, inst, leaf)) return leaf;
    for (const float angle : kLeafTurns) {
        PatchLeaf turned = leaf;
        turned.direction = Eigen::AngleAxisf(angle, leaf.normal) * leaf.direction;
        if (leaf_seen(lobe, inst, turned)) return turned;
    }
    return std::nullopt;
}

// How a tree that stores its leaf area draws its leaves: the share of the offered leaves that
// are seen, as placed or turned (drawn_leaf), which it draws, and the factor on their size. The
// texturing fitted the patches with their leaves at the species' size, their tips reaching a
// lobe's outer cells, but the offered leaves hold several times the stored area (the palm's 111
// times). Shrinking every blade to that area pulled the crown's rim in (the palm's 0.6 m
// leaflets were drawn 0.16-0.18 m long, docs/rebuild.md), so the leaves keep their size and are
// thinned instead; only when the seen leaves hold less than the area are they enlarged.
struct LeafPlan {
    double drawn_share = 1;
    float size = 1;
};

LeafPlan plan_leaf_area(const LobeTree& tree, const TexturedTree& textured, const std::vector<double>& leaf_weight) {
    double seen_area = 0;
    for (std::size_t l = 0; l < textured.lobes.size(); ++l)
        for (const auto& inst : textured.lobes[l].instances) {
            const Patch& patch = textured.library.patches[inst.patch];
            const std::size_t offered = offered_leaves(patch, textured.leaf_share, leaf_weight, l);
            for (std::size_t i = 0; i < offered; ++i)
                if (drawn_leaf(tree.lobes[l], inst, patch.leaves[i]))
                    seen_area += static_cast<double>(blade_area(patch.leaves[i], textured.library.leaf_shape));
        }
    if (!(seen_area > 0)) return {};
    const double ratio = tree.leaf_area_m2 / seen_area;
    return {std::min(1.0, ratio), static_cast<float>(std::sqrt(std::max(1.0, ratio)))};
}

std::size_t prefix(double fraction, std::size_t n) {
    return std::min(n, static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(n))));
}

void draw_leaf(const TexturedTree& textured, const PatchInstance& inst, const PatchLeaf& leaf, float enlarge, SynthesizedMesh& out) {
    add_leaf(out.leaves, inst.apply(leaf.base), inst.rotation * leaf.direction, inst.rotation * leaf.normal, leaf.length * enlarge,
             leaf.width * enlarge, textured.library.leaf_shape);
    ++out.leaf_count;
}

// Stochastic pruning: of each patch a prefix of its shuffled leaves, enlarged to keep the leaf
// area of the level of detail.
void draw_pruned_leaves(const TexturedTree& textured, const std::vector<double>& leaf_weight, double fraction, SynthesizedMesh& out) {
    for (std::size_t l = 0; l < textured.lobes.size(); ++l)
        for (const auto& inst : textured.lobes[l].instances) {
            const Patch& patch = textured.library.patches[inst.patch];
            const std::size_t pruned = kept_leaves(fraction * textured.leaf_share, patch.leaves.size());
            const float enlarge = pruned > 0 ? std::sqrt(static_cast<float>(patch.leaves.size()) / static_cast<float>(pruned)) : 1.0f;
            const std::size_t kept = offered_leaves(patch, fraction * textured.leaf_share, leaf_weight, l);
            for (std::size_t i = 0; i < kept; ++i) draw_leaf(textured, inst, patch.leaves[i], enlarge, out);
        }
}

// A tree that stores its leaf area: the plan's share of each patch's seen leaves, of them the
// level of detail's fraction (a prefix of the shuffled leaves, enlarged by 1 / sqrt(fraction) to
// keep the area). Counts are rounded down with the remainder carried to the next patch, so the
// tree draws its share whatever the patches' sizes.
void draw_planned_leaves(const LobeTree& tree, const TexturedTree& textured, const std::vector<double>& leaf_weight, double fraction,
                         SynthesizedMesh& out) {
    const LeafPlan plan = plan_leaf_area(tree, textured, leaf_weight);
    const float enlarge = plan.size / std::sqrt(static_cast<float>(fraction));
    double carried = 0;
    for (std::size_t l = 0; l < textured.lobes.size(); ++l)
        for (const auto& inst : textured.lobes[l].instances) {
            const Patch& patch = textured.library.patches[inst.patch];
            carried += fraction * plan.drawn_share * static_cast<double>(offered_leaves(patch, textured.leaf_share, leaf_weight, l));
            const auto kept = std::min(patch.leaves.size(), static_cast<std::size_t>(std::floor(carried)));
            carried -= static_cast<double>(kept);
            for (std::size_t i = 0; i < kept; ++i)
                if (const auto leaf = drawn_leaf(tree.lobes[l], inst, patch.leaves[i])) draw_leaf(textured, inst, *leaf, enlarge, out);
        }
}

}  // namespace

TriangleMesh SynthesizedMesh::combined() const {
    TriangleMesh all = wood;
    all.append(leaves);
    return all;
}

TexturedTree texture_tree(const LobeTree& tree, const SpeciesProfile& species, const SynthesisOptions& o) {
    TexturedTree out;
    out.library = build_patch_library(species, o.library);
    out.lobes.resize(tree.lobes.size());
    // A lobe's share of the budget goes by the volume it is to fill: its occupied cells' when the
    // .tlobe recorded where its points were, else its hull's.
    std::vector<double> fill_volume(tree.lobes.size());
    double total_volume = 0;
    for (std::size_t i = 0; i < tree.lobes.size(); ++i) {
        const Lobe& lobe = tree.lobes[i];
        fill_volume[i] = std::max(lobe.volume(), 0.0);
        if (!lobe.occupancy.empty())
            fill_volume[i] = std::min(fill_volume[i], static_cast<double>(lobe.occupancy.occupied_count()) *
                                                              std::pow(static_cast<double>(lobe.occupancy.cell), 3));
        total_volume += fill_volume[i];
    }
    // Triangles per patch, on average over the library. Leafy species (compound leaves,
    // needles) carry several times more leaf than twig triangles per patch; their leaves are
    // thinned to at most the twig triangles (stochastic pruning, enlarged to keep the leaf
    // area, as for the LOD) so that the budget buys patches that reach the whole lobe.
    double wood = 0, leaf = 0;
    for (const Patch& p : out.library.patches) {
        wood += 2.0 * static_cast<double>(p.segments.size()) * o.twig_sides;
        leaf += 2.0 * static_cast<double>(p.leaves.size());
    }
    out.leaf_share = leaf > wood && leaf > 0 ? std::max(wood / leaf, kMinLeafShare) : 1.0;
    double mean_triangles = 0;  // per patch, as drawn
    for (const Patch& p : out.library.patches) mean_triangles += static_cast<double>(patch_triangles(p, o.twig_sides, out.leaf_share));
    mean_triangles = std::max(1.0, mean_triangles / static_cast<double>(std::max<std::size_t>(out.library.patches.size(), 1)));
    // The budget is a hard bound on the whole mesh: the main skeleton's generalized cylinders
    // come first, the patches get the rest, counted patch by patch (lobes/texturing.hpp).
    const std::size_t skeleton_triangles = tree.skeleton.size() >= 2 ? build_branch_mesh(tree.skeleton, o.main_branches).faces.size() : 0;
    out.patch_budget = o.max_triangles > skeleton_triangles ? o.max_triangles - skeleton_triangles : 0;
    const double budget = static_cast<double>(out.patch_budget);
    // Every lobe first gets a floor (kMinPatchesPerLobe patches, less when the budget is short)
    // and the rest by volume.
    const double lobes = static_cast<double>(std::max<std::size_t>(tree.lobes.size(), 1));
    const double floor_triangles = std::floor(std::min(kMinPatchesPerLobe * mean_triangles, budget / lobes));
    const double shared = std::max(0.0, budget - floor_triangles * lobes);
    // Budget allocation: every lobe first gets its share of the tree's triangles; the triangles
    // that lobes filled before spending their share are then handed to the lobes that ran out,
    // again by volume (a lobe's texturing is a sequential process, so the larger budget extends
    // the same fill - determinism is kept). Without the second round the big crown lobes
    // stopped half-filled while the triangle budget was far from spent. Shares are rounded
    // down, so the lobes' budgets never sum above the tree's.
    auto texture = [&](std::size_t i, std::size_t triangles) {
        const Lobe& lobe = tree.lobes[i];
        const DockingPoint seed{tree.seed_position(lobe), lobe.seed_direction, std::max(tree.seed_thickness(lobe), 0.002f)};
        TexturingOptions lobe_options = o.texturing;
        lobe_options.max_triangles = triangles;
        lobe_options.twig_sides = o.twig_sides;
        lobe_options.leaf_share = out.leaf_share;
        // Fill cells scaled to the budget: with fewer patches than cells, the growth from the
        // seed never meets filled cells, so it fills the lobe densely near the seed and stops
        // half-way; with about kCellsPerPatch cells per patch, docking points in filled parts
        // are dropped and the patches spread over the whole lobe (measured: 1 cell per patch
        // leaves budget unspent, 4 leaves small lobes sparse).
        const double patches =
                std::min(static_cast<double>(o.texturing.max_patches_per_lobe), static_cast<double>(triangles) / mean_triangles);
        lobe_options.max_fill_cells = std::min(o.texturing.max_fill_cells, std::max(1.0, kCellsPerPatch * patches));
        out.lobes[i] = texture_lobe(lobe.mesh, seed, out.library, lobe_options, i, &lobe.occupancy);
    };
    auto share = [&](std::size_t i, double volume) { return volume > 0 ? fill_volume[i] / volume : 1.0 / lobes; };
    std::vector<std::size_t> caps(tree.lobes.size());
    for (std::size_t i = 0; i < tree.lobes.size(); ++i)
        caps[i] = static_cast<std::size_t>(floor_triangles + std::floor(share(i, total_volume) * shared));
    treelobes::parallel_for(std::size_t{0}, tree.lobes.size(), [&](std::size_t i) { texture(i, caps[i]); });
    // Spare: what the filled lobes left of the budget; the starved lobes keep their caps.
    double spare = budget, starved_volume = 0;
    std::vector<std::size_t> starved;  // lobes that spent their whole budget below the fill target
    for (std::size_t i = 0; i < tree.lobes.size(); ++i) {
        if (out.lobes[i].budget_spent && out.lobes[i].instances.size() < o.texturing.max_patches_per_lobe) {
            starved.push_back(i);
            starved_volume += fill_volume[i];
            spare -= static_cast<double>(caps[i]);
        } else {
            spare -= static_cast<double>(out.lobes[i].triangles);
        }
    }
    if (spare >= mean_triangles && !starved.empty())
        treelobes::parallel_for(std::size_t{0}, starved.size(), [&](std::size_t k) {
            const std::size_t i = starved[k];
            texture(i, caps[i] + static_cast<std::size_t>(std::floor(share(i, starved_volume) * spare)));
        });
    return out;
}

SynthesizedMesh synthesized_mesh(const LobeTree& tree, const TexturedTree& textured, double fraction, const SynthesisOptions& o) {
    if (!(fraction > 0 && fraction <= 1)) throw Error::usage("synthesis: --lod must be in (0, 1], got " + std::to_string(fraction));
    if (o.twig_sides < 3 || o.twig_sides > 16) throw Error::usage("synthesis: twig sides must be 3..16");
    SynthesizedMesh out;
    out.wood.origin = out.leaves.origin = tree.skeleton.origin;

    // Main skeleton: the thickest fraction of the edges (ties: pre-order, parents first).
    const std::size_t n = tree.skeleton.size();
    if (n >= 2) {
        std::vector<int> nodes(n - 1);
        std::iota(nodes.begin(), nodes.end(), 1);
        std::stable_sort(nodes.begin(), nodes.end(),
                         [&](int a, int b) { return tree.skeleton.nodes[a].radius > tree.skeleton.nodes[b].radius; });
        std::vector<bool> keep(n, false);
        keep[0] = true;
        out.skeleton_edges = std::max<std::size_t>(1, prefix(fraction, nodes.size()));
        for (std::size_t i = 0; i < out.skeleton_edges; ++i) keep[nodes[i]] = true;
        for (std::size_t u = 1; u < n; ++u)  // a thickness tie could leave a parent out: close upward
            if (keep[u])
                for (int p = tree.skeleton.nodes[u].parent; p > 0 && !keep[p]; p = tree.skeleton.nodes[p].parent) keep[p] = true;
        std::vector<int> new_index;
        const TreeGraph reduced = keep_nodes(tree.skeleton, keep, new_index);
        if (reduced.size() >= 2) out.wood = build_branch_mesh(reduced, o.main_branches);
        out.wood.origin = tree.skeleton.origin;
    }

    // Twig segments: the thickest fraction over all placed patches.
    std::vector<float> thickness;
    for (const auto& lobe : textured.lobes)
        for (const auto& inst : lobe.instances)
            for (const auto& s : textured.library.patches[inst.patch].segments) thickness.push_back(s.thickness_a * inst.scale);
    float min_thickness = 0;
    if (!thickness.empty() && fraction < 1) {
        const std::size_t kept = std::max<std::size_t>(1, prefix(fraction, thickness.size()));
        std::nth_element(thickness.begin(), thickness.begin() + static_cast<std::ptrdiff_t>(kept - 1), thickness.end(), std::greater<>());
        min_thickness = thickness[kept - 1];
    }
    const std::vector<double> leaf_weight = lobe_leaf_weights(tree, textured);
    const bool stored_area = tree.leaf_area_m2 > 0;
    for (std::size_t l = 0; l < textured.lobes.size(); ++l)
        for (const auto& inst : textured.lobes[l].instances)
            for (const auto& s : textured.library.patches[inst.patch].segments) {
                if (s.thickness_a * inst.scale < min_thickness) continue;
                // As its leaves (leaf_seen), a rebuilt tree's twigs stay where the scan saw its lobe.
                const Occupancy& seen = tree.lobes[l].occupancy;
                if (stored_area && !seen.empty() && !seen.occupied(inst.apply(0.5f * (s.a + s.b)))) continue;
                add_prism(out.wood, inst.apply(s.a), inst.apply(s.b), std::max(0.5f * s.thickness_a * inst.scale, kMinTwigRadius),
                          std::max(0.5f * s.thickness_b * inst.scale, kMinTwigRadius), o.twig_sides);
                ++out.twig_segments;
            }
    if (stored_area) {
        draw_planned_leaves(tree, textured, leaf_weight, fraction, out);
        scale_leaves_to_area(out.leaves, tree.leaf_area_m2, textured.library.leaf_shape);
    } else {
        draw_pruned_leaves(textured, leaf_weight, fraction, out);
    }
    return out;
}

}  // namespace treelobes::lobes
