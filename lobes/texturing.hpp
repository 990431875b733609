// Lobe texturing (Livny et al. 2011, §5, Fig. 5/6): filling each lobe with branchlet patches from the
// species' patch library, starting at the lobe's seed point.
//
// A queue of docking points starts with the seed (p_i, its thickness and direction). For each
// docking point d:
//   - patch selection: the `candidates` patches with the smallest mismatch
//       cost = max(t_r, t_d) / min(t_r, t_d) * (2 - v_r . v_d)
//     (the paper's fit d, written as a cost: 1 for a patch of equal root thickness t_r and
//     orientation v_r, growing with the thickness ratio and the angle between them);
//   - patch fitting: each candidate is placed at d (root onto the docking point, v_r turned
//     onto v_d, scaled by t_d / t_r, turned about v_d by a random angle) and scored by how much
//     of its geometry lies inside the lobe and how many empty lobe cells it reaches; the best
//     one is added, and those of its docking points that lie inside the lobe join the queue.
// Docking points are taken thickest first, so the large structure is laid before twigs fill
// in; a docking point whose best patch only reaches lobe cells that already hold geometry is
// set aside (that part of the lobe is filled), so the patches spread over the whole lobe first;
// once the lobe is filled the set-aside docks are taken up for a second patch per cell.
// The triangle budget is a hard bound: a patch is placed only when its triangles fit.
// Patches without docking points end a path. When the queue runs dry while part of the lobe is
// still empty, a new docking point is taken on the placed twig nearest to the empty region
// (pointing into it; empty cells on the lobe surface first), until the lobe is filled (`fill_target`) or the patch budget is spent;
// such re-seeds are also interleaved with the queue (`reseed_every`), so that a budget too small
// for the whole lobe is spread over it rather than spent around the seed.
// With the lobe's occupancy (lobes/occupancy.hpp, the cells that held scan points), only the
// fill cells that overlap occupied cells are to be filled: fitting scores, dropping of
// redundant docking points, re-seeding and the fill target all count those cells, and the fill
// cells are sized by their volume, so the budget goes where the scan saw the crown rather than
// into the hull's empty space.
// Deterministic for a seed (per-lobe random streams; lobes are independent).
#pragma once

#include "core/triangle_mesh.hpp"
#include "lobes/occupancy.hpp"
#include "lobes/patch_library.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <cstddef>
#include <memory>
#include <vector>

namespace treelobes::lobes {

// Inside test of a closed, outward mesh by ray parity along +z, pre-computed on a grid.
class LobeVolume {
public:
    // `resolution` cells along the mesh's longest side.
    LobeVolume(const TriangleMesh& closed_mesh, int resolution = 40);
    // Cubic cells of `cell_size` metres.
    static LobeVolume with_cell_size(const TriangleMesh& closed_mesh, float cell_size);
    bool inside(const Eigen::Vector3f& p) const;
    // Cell index of p, -1 outside the grid.
    int cell(const Eigen::Vector3f& p) const;
    int cell_count() const { return static_cast<int>(inside_.size()); }
    bool cell_inside(int c) const { return inside_[c] != 0; }
    Eigen::Vector3f cell_centre(int c) const;
    int inside_cells() const { return inside_count_; }

private:
    LobeVolume() = default;
    void build(const TriangleMesh& mesh, float cell_size);
    Eigen::Vector3f lo_;
    float size_ = 1;
    int n_[3] = {1, 1, 1};
    std::vector<char> inside_;
    int inside_count_ = 0;
};

struct TexturingOptions {
    std::uint64_t seed = 1;
    int candidates = 8;                         // patches fitted per docking point
    std::size_t max_patches_per_lobe = 100000;  // a safety bound; the triangle budget governs
    std::size_t max_triangles = SIZE_MAX;       // a hard bound: patches are placed only while their triangles
                                                // (patch_triangles with the two values below) fit
    int twig_sides = 3;                         // as the synthesized mesh draws the patches
    double leaf_share = 1;
    double fill_cell = 0.04;            // metres: edge of the fill cells at least ...
    double max_fill_cells = 60000;      // ... enlarged so that a lobe has at most about this many
                                        // (texture_tree sets it to 2 per budgeted patch)
    double fill_target = 0.95;          // fraction of lobe cells reached by twigs or leaves
    double max_reseeds_per_cell = 2.0;  // extra docking points for empty regions, per lobe cell
    // While the queue still holds docking points, one re-seed into the next empty region after
    // this many placed patches (0 = only when the queue runs dry). A lobe whose budget runs out
    // before it is filled then has its patches spread over all of it instead of a dense ball
    // around the seed: a tall conifer lobe was cut 3-5 m below its top (docs/rebuild.md).
    int reseed_every = 2;
    // A docking point takes its best-fitting patch only when at least this share of the patch's
    // geometry lies inside the lobe (Livny et al. 2011, Sec. 5: the fit measures the patch
    // against the lobe's geometry); otherwise the docking point stays unused. Seeds and re-seeds
    // always take theirs (a re-seed is first fitted thinner). At 0 a long patch at the lobe's rim
    // stuck out of the crown: the pine's whorl tips and the terminalia's tiers (docs/rebuild.md).
    double min_inside_share = 0.7;
};

struct PatchInstance {
    int patch = 0;
    Eigen::Quaternionf rotation = Eigen::Quaternionf::Identity();
    float scale = 1;
    Eigen::Vector3f translation{0, 0, 0};
    Eigen::Vector3f apply(const Eigen::Vector3f& p) const { return translation + scale * (rotation * p); }
};

struct LobeTexture {
    std::vector<PatchInstance> instances;
    std::size_t docks_used = 0;
    std::size_t docks_outside = 0;    // docking points outside the lobe, or whose best patch would stick out of it: not used
    std::size_t docks_redundant = 0;  // docking points whose best patch reaches no cell short of patches
    std::size_t reseeds = 0;
    double filled = 0;             // fraction of lobe cells (occupied ones, with an occupancy) reached
    std::size_t triangles = 0;     // of the placed patches (patch_triangles), <= max_triangles
    bool budget_spent = false;     // stopped by max_triangles or max_patches_per_lobe, not by the fill
    std::size_t target_cells = 0;  // fill cells to be reached
};

// Textures one lobe (closed mesh) from its seed. `stream` selects the random stream (the lobe
// index). `occupancy` may be null or empty (then the whole lobe is filled).
LobeTexture texture_lobe(const TriangleMesh& lobe, const DockingPoint& seed, const PatchLibrary& library, const TexturingOptions& options,
                         std::uint64_t stream, const Occupancy* occupancy = nullptr);

}  // namespace treelobes::lobes
