// Full-tree synthesis from a lobe-based representation (Livny et al. 2011, §5) and its level of detail
// (§6.2).
//
// texture_tree() builds the species' patch library and textures every lobe from its seed
// (lobes/texturing.hpp), each lobe in its own random stream so the result is the same for any
// thread count. The tree's triangle budget (max_triangles, a hard bound on the mesh: the main
// skeleton's cylinders first, then every placed patch counted) is shared by the lobes in
// proportion to their volume (at least 20 mean patches each when it allows); the share that
// lobes leave unspent goes to the lobes that spent theirs. Where a species' patches carry more
// leaf than twig triangles, the leaves are thinned to the twig triangles (leaf_share, enlarged
// to keep the area), so the budget buys more patches. synthesized_mesh() turns the main skeleton into generalized cylinders
// (geometry/branch_mesh.hpp) and the placed patches into twig prisms and leaf blades.
//
// LOD (fraction f in (0, 1]): the elements are ordered once -
//   - skeleton edges by thickness (thickest first; with allometric diameters a prefix is
//     always a connected subtree);
//   - twig segments of all patches by thickness;
//   - the leaves of every patch in their random library order (stochastic pruning: a prefix
//     of ceil(f n) leaves is kept and enlarged by sqrt(n / kept) so the leaf area stays)
// and a reduced mesh keeps the first fraction f of each list.
//
// A tree that stores its leaf area (LobeTree::leaf_area_m2 > 0: a `treelobes rebuild` of a mesh
// with leaves) draws leaves and twigs only where its lobes' occupancy saw the crown (a leaf's
// tip, a twig's middle in an occupied cell; a leaf pointing out of the seen cells is turned
// about its base, in its blade's plane, into them when it can), and gives exactly that area at
// every level of detail: its leaves keep the species' size and are thinned when the patches
// offer more, and are enlarged about their bases only when they offer less. Otherwise the
// blades keep the sizes of the species' patches.
#pragma once

#include "config/species_profile.hpp"
#include "core/triangle_mesh.hpp"
#include "geometry/branch_mesh.hpp"
#include "lobes/lobe_tree.hpp"
#include "lobes/patch_library.hpp"
#include "lobes/texturing.hpp"

#include <string>
#include <utility>
#include <vector>

namespace treelobes::lobes {

struct SynthesisOptions {
    PatchLibraryOptions library;
    TexturingOptions texturing;
    std::size_t max_triangles = 2000000;  // triangles of the whole synthesized mesh at most (Livny et al. 2011: 0.5-3 M
                                          // per tree): the main skeleton's, the rest shared by the lobes by volume
    BranchMeshOptions main_branches{8, 2, 0.002f, 1.0f, 0.0f, true};
    int twig_sides = 3;  // prism sides of patch twigs
};

struct TexturedTree {
    PatchLibrary library;
    std::vector<LobeTexture> lobes;  // one per LobeTree::lobes entry
    double leaf_share = 1;           // fraction of each patch's leaves drawn (budget thinning, area kept)
    std::size_t patch_budget = 0;    // triangles left for the patches after the main skeleton
};

TexturedTree texture_tree(const LobeTree& tree, const SpeciesProfile& species, const SynthesisOptions& options = {});

struct SynthesizedMesh {
    TriangleMesh wood;    // main branches and twigs, the tree's origin
    TriangleMesh leaves;  // leaf blades, the tree's origin
    std::size_t skeleton_edges = 0, twig_segments = 0, leaf_count = 0;
    TriangleMesh combined() const;
    std::size_t triangles() const { return wood.faces.size() + leaves.faces.size(); }
};

// The mesh at level of detail `fraction` (1 = everything). Throws Error(Usage) for a fraction
// outside (0, 1].
SynthesizedMesh synthesized_mesh(const LobeTree& tree, const TexturedTree& textured, double fraction = 1.0,
                                 const SynthesisOptions& options = {});

}  // namespace treelobes::lobes
