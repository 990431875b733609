#include "lobes/texturing.hpp"

#include "core/error.hpp"
#include "core/random.hpp"
#include "geometry/kd_tree.hpp"

#include <algorithm>
#include <cmath>
#include <queue>
#include <numbers>
#include <numeric>

namespace treelobes::lobes {

namespace {

constexpr float kMinScale = 0.5f, kMaxScale = 2.0f;  // patches are stretched at most this much to fit a docking point
constexpr float kPatchReach = 40.0f;                 // a patch reaches about this many root thicknesses
constexpr int kPatchesPerCell = 2;                   // a fill cell takes geometry from this many patches at most
constexpr std::size_t kFitLeaves = 32;               // leaf tips per patch scored in fitting (a uniform prefix)

// Points of a patch used for fitting: segment ends and leaf tips, with the thickness there.
struct Sample {
    Eigen::Vector3f position;
    float thickness;
};

// At most `max_leaves` leaf tips: patch leaves are shuffled, so a prefix is a uniform subsample
// (needle patches carry hundreds; scoring them all made fitting dominate the texturing time).
std::vector<Sample> patch_samples(const Patch& patch, std::size_t max_leaves) {
    std::vector<Sample> samples;
    // Points along each segment at most the grown segment length apart: a simplified axis has
    // long segments, and their ends alone would miss the cells they pass through.
    for (const auto& s : patch.segments) {
        const float length = (s.b - s.a).norm();
        const int n = patch.step > 0 ? std::max(1, static_cast<int>(std::ceil(length / patch.step - 1e-3f))) : 1;
        for (int k = 1; k <= n; ++k) {
            const float f = static_cast<float>(k) / static_cast<float>(n);
            samples.push_back({s.a + f * (s.b - s.a), s.thickness_a + f * (s.thickness_b - s.thickness_a)});
        }
    }
    for (std::size_t i = 0; i < std::min(max_leaves, patch.leaves.size()); ++i) {
        const auto& l = patch.leaves[i];
        samples.push_back({l.base + l.length * l.direction, 0.0f});
    }
    return samples;
}

float mismatch(const Patch& patch, const DockingPoint& d) {
    const float a = std::max(patch.root_thickness, 1e-6f), b = std::max(d.thickness, 1e-6f);
    return std::max(a, b) / std::min(a, b) * (2.0f - patch.root_direction.dot(d.direction));
}

PatchInstance place(const Patch& patch, const DockingPoint& d, float spin) {
    PatchInstance inst;
    inst.rotation = Eigen::AngleAxisf(spin, d.direction) * Eigen::Quaternionf::FromTwoVectors(patch.root_direction, d.direction);
    inst.scale = std::clamp(d.thickness / std::max(patch.root_thickness, 1e-6f), kMinScale, kMaxScale);
    inst.translation = d.position;
    return inst;
}

}  // namespace

namespace {

std::pair<Eigen::Vector3f, Eigen::Vector3f> bounds(const TriangleMesh& mesh) {
    if (mesh.faces.empty()) throw Error::usage("lobe volume: needs a closed mesh");
    Eigen::Vector3f lo = mesh.vertices[0], hi = mesh.vertices[0];
    for (const auto& v : mesh.vertices) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
    }
    return {lo, hi};
}

}  // namespace

// Fill cells to be reached: the lobe's inside cells; with an occupancy, those of them that
// overlap an occupied cell (centre in an occupied cell, or an occupied cell's centre inside
// them - occupancy cells may be larger or smaller than fill cells). When no inside cell
// overlaps one (points outside the simplified hull), the whole lobe.
static std::vector<char> fill_targets(const LobeVolume& grid, const Occupancy* occupancy) {
    std::vector<char> target(grid.cell_count(), 0);
    for (int c = 0; c < grid.cell_count(); ++c) target[c] = grid.cell_inside(c) ? 1 : 0;
    if (occupancy == nullptr) return target;
    std::vector<char> overlap(grid.cell_count(), 0);
    for (int c = 0; c < grid.cell_count(); ++c) overlap[c] = target[c] && occupancy->occupied(grid.cell_centre(c)) ? 1 : 0;
    for (std::size_t i = 0; i < occupancy->bits.size(); ++i) {
        if (!occupancy->bits[i]) continue;
        const int c = grid.cell(occupancy->cell_centre(i));
        if (c >= 0 && target[c]) overlap[c] = 1;
    }
    if (std::find(overlap.begin(), overlap.end(), 1) == overlap.end()) return target;
    return overlap;
}

LobeVolume::LobeVolume(const TriangleMesh& mesh, int resolution) {
    if (resolution < 1) throw Error::usage("lobe volume: resolution must be >= 1");
    const auto [lo, hi] = bounds(mesh);
    build(mesh, (hi - lo).maxCoeff() / static_cast<float>(resolution));
}

LobeVolume LobeVolume::with_cell_size(const TriangleMesh& mesh, float cell_size) {
    LobeVolume v;
    v.build(mesh, cell_size);
    return v;
}

void LobeVolume::build(const TriangleMesh& mesh, float cell_size) {
    const auto [lo, hi] = bounds(mesh);
    size_ = std::max(cell_size, 1e-4f);
    lo_ = lo - Eigen::Vector3f::Constant(0.5f * size_);
    for (int k = 0; k < 3; ++k) n_[k] = static_cast<int>(std::ceil((hi[k] - lo_[k]) / size_)) + 1;
    inside_.assign(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2], 0);
    // Crossings of each vertical ray (through the cell centres of a column) with the surface:
    // a face whose outward normal points down is entered going up (+1), otherwise left (-1).
    // The rays are nudged off the cell centres so that they miss edges and vertices.
    std::vector<std::vector<std::pair<float, int>>> crossings(static_cast<std::size_t>(n_[0]) * n_[1]);
    const Eigen::Vector2f nudge(0.0137f * size_, 0.0291f * size_);
    for (const auto& f : mesh.faces) {
        const Eigen::Vector3f &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
        const float nz = (b - a).cross(c - a).z();
        if (nz == 0) continue;  // vertical faces: rays run along them
        const Eigen::Vector3f flo = a.cwiseMin(b).cwiseMin(c), fhi = a.cwiseMax(b).cwiseMax(c);
        const int i0 = std::max(0, static_cast<int>(std::floor((flo.x() - lo_.x()) / size_ - 0.5f)));
        const int i1 = std::min(n_[0] - 1, static_cast<int>(std::ceil((fhi.x() - lo_.x()) / size_ - 0.5f)));
        const int j0 = std::max(0, static_cast<int>(std::floor((flo.y() - lo_.y()) / size_ - 0.5f)));
        const int j1 = std::min(n_[1] - 1, static_cast<int>(std::ceil((fhi.y() - lo_.y()) / size_ - 0.5f)));
        for (int i = i0; i <= i1; ++i)
            for (int j = j0; j <= j1; ++j) {
                const Eigen::Vector2f p = lo_.head<2>() + Eigen::Vector2f((i + 0.5f) * size_, (j + 0.5f) * size_) + nudge;
                auto edge = [&](const Eigen::Vector3f& u, const Eigen::Vector3f& v) {
                    return (v.x() - u.x()) * (p.y() - u.y()) - (v.y() - u.y()) * (p.x() - u.x());
                };
                const float w0 = edge(b, c), w1 = edge(c, a), w2 = edge(a, b);
                const bool in = nz > 0 ? (w0 >= 0 && w1 >= 0 && w2 >= 0) : (w0 <= 0 && w1 <= 0 && w2 <= 0);
                if (!in) continue;
                const float z = (w0 * a.z() + w1 * b.z() + w2 * c.z()) / (w0 + w1 + w2);
                crossings[static_cast<std::size_t>(i) * n_[1] + j].emplace_back(z, nz < 0 ? 1 : -1);
            }
    }
    for (int i = 0; i < n_[0]; ++i)
        for (int j = 0; j < n_[1]; ++j) {
            auto& column = crossings[static_cast<std::size_t>(i) * n_[1] + j];
            std::sort(column.begin(), column.end());
            int winding = 0;
            std::size_t next = 0;
            for (int k = 0; k < n_[2]; ++k) {
                const float z = lo_.z() + (k + 0.5f) * size_;
                while (next < column.size() && column[next].first <= z) winding += column[next++].second;
                if (winding > 0) {
                    inside_[(static_cast<std::size_t>(i) * n_[1] + j) * n_[2] + k] = 1;
                    ++inside_count_;
                }
            }
        }
}

int LobeVolume::cell(const Eigen::Vector3f& p) const {
    int idx[3];
    for (int k = 0; k < 3; ++k) {
        idx[k] = static_cast<int>(std::floor((p[k] - lo_[k]) / size_));
        if (idx[k] < 0 || idx[k] >= n_[k]) return -1;
    }
    return (idx[0] * n_[1] + idx[1]) * n_[2] + idx[2];
}

bool LobeVolume::inside(const Eigen::Vector3f& p) const {
    const int c = cell(p);
    return c >= 0 && inside_[c];
}

Eigen::Vector3f LobeVolume::cell_centre(int c) const {
    const int k = c % n_[2], j = (c / n_[2]) % n_[1], i = c / (n_[2] * n_[1]);
    return lo_ + size_ * Eigen::Vector3f(i + 0.5f, j + 0.5f, k + 0.5f);
}

LobeTexture texture_lobe(const TriangleMesh& lobe, const DockingPoint& seed, const PatchLibrary& library,
                         const TexturingOptions& o, std::uint64_t stream, const Occupancy* occupancy) {
    if (library.patches.empty()) throw Error::usage("lobe texturing: the patch library is empty");
    if (o.candidates < 1) throw Error::usage("lobe texturing: candidates must be >= 1");
    if (!(o.fill_cell > 0) || !(o.max_fill_cells >= 1)) throw Error::usage("lobe texturing: fill cell and cell count must be positive");
    LobeTexture texture;
    const LobeVolume volume(lobe, 40);
    const bool occupied_only = occupancy != nullptr && !occupancy->empty();
    // The volume to fill: the occupied cells' (at most the lobe's) with an occupancy.
    double fill_volume = std::max(lobe.signed_volume(), 0.0);
    if (occupied_only)
        fill_volume = std::min(fill_volume, static_cast<double>(occupancy->occupied_count()) * std::pow(static_cast<double>(occupancy->cell), 3));
    const double cell = std::max(o.fill_cell, std::cbrt(fill_volume / o.max_fill_cells));
    const LobeVolume fill_grid = LobeVolume::with_cell_size(lobe, static_cast<float>(cell));
    const std::vector<char> target = fill_targets(fill_grid, occupied_only ? occupancy : nullptr);
    std::vector<int> filled(fill_grid.cell_count(), 0);  // patches reaching each cell
    int filled_count = 0;
    const int fill_total = std::max(1, static_cast<int>(std::count(target.begin(), target.end(), 1)));
    texture.target_cells = static_cast<std::size_t>(fill_total);
    Rng rng(o.seed * 0x2545f4914f6cdd1dULL + stream * 0x9e3779b97f4a7c15ULL + 17);

    std::vector<std::vector<Sample>> samples(library.patches.size()), fit_samples(library.patches.size());
    for (std::size_t i = 0; i < library.patches.size(); ++i) {
        samples[i] = patch_samples(library.patches[i], library.patches[i].leaves.size());
        fit_samples[i] = patch_samples(library.patches[i], kFitLeaves);
    }
    // Twig points of every placed patch: re-seeding grows from the nearest one to an empty cell
    // (a scan over all placed points made re-seeding quadratic in big lobes).
    GrowingKdTree twigs;

    // Empty lobe cells in a fixed random order: the order in which empty regions are re-seeded.
    std::vector<int> fill_order;
    for (int c = 0; c < fill_grid.cell_count(); ++c)
        if (target[c]) fill_order.push_back(c);
    for (std::size_t i = fill_order.size(); i > 1; --i) std::swap(fill_order[i - 1], fill_order[rng.next() % i]);
    // Cells on the lobe's surface first: the hull runs through the cluster's outermost points
    // (alpha-shape vertices are input points), where a scan sees the foliage, while much of a
    // large hull's inside is empty space.
    auto on_surface = [&](int c) {
        const Eigen::Vector3f centre = fill_grid.cell_centre(c);
        for (int axis = 0; axis < 3; ++axis)
            for (const float step : {-1.0f, 1.0f}) {
                const int n = fill_grid.cell(centre + step * static_cast<float>(cell) * Eigen::Vector3f::Unit(axis));
                if (n < 0 || !fill_grid.cell_inside(n)) return true;
            }
        return false;
    };
    std::stable_partition(fill_order.begin(), fill_order.end(), on_surface);
    std::size_t fill_cursor = 0;

    // Docking points, thickest first (the large structure is laid before the twigs fill in);
    // ties in order of creation. Forced docks (the seed and re-seeds) are used even where
    // they sit outside the lobe or add nothing new.
    struct Pending {
        DockingPoint dock;
        bool forced;
        std::size_t order;
    };
    auto later = [](const Pending& a, const Pending& b) {
        return a.dock.thickness != b.dock.thickness ? a.dock.thickness < b.dock.thickness : a.order > b.order;
    };
    std::priority_queue<Pending, std::vector<Pending>, decltype(later)> queue(later);
    std::size_t created = 0;
    queue.push({seed, true, created++});
    std::vector<int> order;
    order.reserve(library.patches.size());
    int layer = 1;                                    // patches a cell takes in the current pass
    std::vector<Pending> deferred;                    // docks dropped as redundant in an earlier pass
    auto reaches = [&](int cell) { return cell >= 0 && target[cell] && filled[cell] < layer; };
    // Triangles each patch adds to the mesh: the budget is a hard bound on their sum.
    std::vector<std::size_t> cost(library.patches.size());
    for (std::size_t i = 0; i < library.patches.size(); ++i) cost[i] = patch_triangles(library.patches[i], o.twig_sides, o.leaf_share);
    const std::size_t min_cost = *std::min_element(cost.begin(), cost.end());
    auto affordable = [&] { return texture.instances.size() < o.max_patches_per_lobe && texture.triangles + min_cost <= o.max_triangles; };
    while (affordable()) {
        if (queue.empty()) {
            // Spread first: cells take one patch until the lobe is filled (or cannot be filled
            // further); then the docks that were dropped for it are taken up again, for a second
            // patch per cell. With a tight budget (big crowns) the patches reach more of the
            // lobe before it runs out; with a loose one the lobe ends as dense as before.
            const bool filled_enough = static_cast<double>(filled_count) / fill_total >= o.fill_target ||
                                       texture.reseeds >= static_cast<std::size_t>(o.max_reseeds_per_cell * fill_total) || twigs.empty();
            while (!filled_enough && fill_cursor < fill_order.size() && filled[fill_order[fill_cursor]]) ++fill_cursor;
            if (filled_enough || fill_cursor == fill_order.size()) {
                if (layer >= kPatchesPerCell || deferred.empty()) break;
                ++layer;
                for (auto& pending : deferred) queue.push(std::move(pending));
                deferred.clear();
                continue;
            }
            const Eigen::Vector3f target = fill_grid.cell_centre(fill_order[fill_cursor++]);
            const Eigen::Vector3f from = twigs.point(twigs.nearest(target));
            const Eigen::Vector3f dir = target - from;
            if (dir.norm() < 1e-5f) continue;
            // As thick as a twig must be to reach the empty cell, never thicker than the seed.
            const float thickness = std::clamp(dir.norm() / kPatchReach, 0.002f, std::max(seed.thickness, 0.002f));
            queue.push({{from, dir.normalized(), thickness}, true, created++});
            ++texture.reseeds;
        }
        const Pending pending = queue.top();
        queue.pop();
        const DockingPoint& d = pending.dock;
        if (!pending.forced && !volume.inside(d.position)) {
            ++texture.docks_outside;
            continue;
        }
        // Patch selection: of the patches that fit the remaining budget, the candidates with the
        // smallest thickness/orientation mismatch.
        order.clear();
        for (std::size_t i = 0; i < library.patches.size(); ++i)
            if (texture.triangles + cost[i] <= o.max_triangles) order.push_back(static_cast<int>(i));
        const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(o.candidates), order.size());
        std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(k), order.end(), [&](int a, int b) {
            const float ca = mismatch(library.patches[a], d), cb = mismatch(library.patches[b], d);
            return ca != cb ? ca < cb : a < b;
        });
        // Patch fitting: geometry inside the lobe, plus lobe cells it newly reaches.
        double best_score = -1;
        int best_reached = 0;
        PatchInstance best;
        for (std::size_t c = 0; c < k; ++c) {
            PatchInstance inst = place(library.patches[order[c]], d, static_cast<float>(rng.uniform(0, 2 * std::numbers::pi)));
            inst.patch = order[c];
            const auto& s = fit_samples[order[c]];
            int inside = 0, reached = 0;
            for (const auto& sample : s) {
                const Eigen::Vector3f p = inst.apply(sample.position);
                inside += volume.inside(p) ? 1 : 0;
                reached += reaches(fill_grid.cell(p)) ? 1 : 0;
            }
            const double score = s.empty() ? 0.0 : (inside + 0.5 * reached) / static_cast<double>(s.size());
            if (score > best_score) {
                best_score = score;
                best_reached = reached;
                best = inst;
            }
        }
        if (!pending.forced && best_reached == 0) {  // this part of the lobe is filled already
            ++texture.docks_redundant;
            if (layer < kPatchesPerCell) deferred.push_back(pending);
            continue;
        }
        texture.instances.push_back(best);
        texture.triangles += cost[best.patch];
        ++texture.docks_used;
        const Patch& patch = library.patches[best.patch];
        for (const auto& sample : samples[best.patch]) {
            const Eigen::Vector3f p = best.apply(sample.position);
            const int cell = fill_grid.cell(p);
            if (reaches(cell) && filled[cell]++ == 0) ++filled_count;
            if (sample.thickness > 0) twigs.add(p);
        }
        for (const auto& dock : patch.docks)
            queue.push({{best.apply(dock.position), best.rotation * dock.direction, dock.thickness * best.scale}, false, created++});
    }
    texture.filled = static_cast<double>(filled_count) / fill_total;
    texture.budget_spent = !affordable();
    return texture;
}

}  // namespace treelobes::lobes
