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
constexpr float kMinRefitThickness = 0.004f;         // metres: a seed or re-seed that sticks out is not made thinner than this
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

namespace {

void check_texturing(const PatchLibrary& library, const TexturingOptions& o) {
    if (library.patches.empty()) throw Error::usage("lobe texturing: the patch library is empty");
    if (o.candidates < 1) throw Error::usage("lobe texturing: candidates must be >= 1");
    if (!(o.fill_cell > 0) || !(o.max_fill_cells >= 1)) throw Error::usage("lobe texturing: fill cell and cell count must be positive");
    if (!(o.min_inside_share >= 0 && o.min_inside_share <= 1)) throw Error::usage("lobe texturing: the inside share of a patch must be in 0..1");
}

// Edge of the fill cells: the volume to fill (the occupied cells', at most the lobe's, with an
// occupancy) in at most max_fill_cells cells, never smaller than fill_cell.
double fill_cell_size(const TriangleMesh& lobe, const TexturingOptions& o, const Occupancy* occupancy) {
    double fill_volume = std::max(lobe.signed_volume(), 0.0);
    if (occupancy != nullptr)
        fill_volume =
                std::min(fill_volume, static_cast<double>(occupancy->occupied_count()) * std::pow(static_cast<double>(occupancy->cell), 3));
    return std::max(o.fill_cell, std::cbrt(fill_volume / o.max_fill_cells));
}

// Target cells in a fixed random order, the order in which empty regions are re-seeded. Cells on
// the lobe's surface first: the hull runs through the cluster's outermost points (alpha-shape
// vertices are input points), where a scan sees the foliage, while much of a large hull's inside
// is empty space.
std::vector<int> reseed_order(const LobeVolume& fill_grid, const std::vector<char>& target, double cell, Rng& rng) {
    std::vector<int> fill_order;
    for (int c = 0; c < fill_grid.cell_count(); ++c)
        if (target[c]) fill_order.push_back(c);
    for (std::size_t i = fill_order.size(); i > 1; --i) std::swap(fill_order[i - 1], fill_order[rng.next() % i]);
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
    return fill_order;
}

// A docking point waiting for a patch: the lobe's seed, a re-seed into an empty region, or a
// docking point of a placed patch. The seed and re-seeds are used even where they sit outside the
// lobe or add nothing new.
enum class DockOrigin { Seed, Reseed, Patch };

struct Pending {
    DockingPoint dock;
    DockOrigin origin;
    std::size_t order;
    bool forced() const { return origin != DockOrigin::Patch; }
};

// Docking points, thickest first (the large structure is laid before the twigs fill in); ties in
// order of creation.
struct Later {
    bool operator()(const Pending& a, const Pending& b) const {
        return a.dock.thickness != b.dock.thickness ? a.dock.thickness < b.dock.thickness : a.order > b.order;
    }
};

// The best of the fitted candidates: its placement and the fill cells it newly reaches.
struct Fit {
    PatchInstance instance;
    int reached = 0;
    double inside_share = 0;
};

// One lobe being textured: the fill plan, the docking-point queue and the patches placed so far.
// The steps are those of the loop in run(): re-seed an empty region when the queue runs dry,
// select candidate patches for a dock, fit them, place the best.
class LobeTexturer {
public:
    LobeTexturer(const TriangleMesh& lobe, const PatchLibrary& library, const TexturingOptions& o, std::uint64_t stream,
                 const Occupancy* occupancy)
            : library_(library),
              o_(o),
              volume_(lobe, 40),
              cell_(fill_cell_size(lobe, o, occupied_or_null(occupancy))),
              fill_grid_(LobeVolume::with_cell_size(lobe, static_cast<float>(cell_))),
              target_(fill_targets(fill_grid_, occupied_or_null(occupancy))),
              filled_(fill_grid_.cell_count(), 0),
              fill_total_(std::max(1, static_cast<int>(std::count(target_.begin(), target_.end(), 1)))),
              rng_(o.seed * 0x2545f4914f6cdd1dULL + stream * 0x9e3779b97f4a7c15ULL + 17) {
        texture_.target_cells = static_cast<std::size_t>(fill_total_);
        samples_.resize(library.patches.size());
        fit_samples_.resize(library.patches.size());
        for (std::size_t i = 0; i < library.patches.size(); ++i) {
            samples_[i] = patch_samples(library.patches[i], library.patches[i].leaves.size());
            fit_samples_[i] = patch_samples(library.patches[i], kFitLeaves);
        }
        fill_order_ = reseed_order(fill_grid_, target_, cell_, rng_);
        // Triangles each patch adds to the mesh: the budget is a hard bound on their sum.
        cost_.resize(library.patches.size());
        for (std::size_t i = 0; i < library.patches.size(); ++i) cost_[i] = patch_triangles(library.patches[i], o.twig_sides, o.leaf_share);
        min_cost_ = *std::min_element(cost_.begin(), cost_.end());
        order_.reserve(library.patches.size());
    }

    LobeTexture run(const DockingPoint& seed) {
        queue_.push({seed, DockOrigin::Seed, created_++});
        while (affordable()) {
            if (queue_.empty()) {
                const Refill refill = refill_queue(seed);
                if (refill == Refill::Done) break;
                if (refill == Refill::Again) continue;
            }
            const Pending pending = queue_.top();
            queue_.pop();
            const DockingPoint& d = pending.dock;
            if (!pending.forced() && !volume_.inside(d.position)) {
                ++texture_.docks_outside;
                continue;
            }
            const Fit best = fit_at(pending);
            if (!pending.forced() && best.inside_share < o_.min_inside_share) {  // it would stick out of the lobe
                ++texture_.docks_outside;
                continue;
            }
            if (!pending.forced() && best.reached == 0) {  // this part of the lobe is filled already
                ++texture_.docks_redundant;
                if (layer_ < kPatchesPerCell) deferred_.push_back(pending);
                continue;
            }
            add(best.instance);
            if (o_.reseed_every > 0 && texture_.instances.size() % static_cast<std::size_t>(o_.reseed_every) == 0) reseed(seed);
        }
        texture_.filled = static_cast<double>(filled_count_) / fill_total_;
        texture_.budget_spent = !affordable();
        return texture_;
    }

private:
    enum class Refill { Done, Again, Reseeded };

    static const Occupancy* occupied_or_null(const Occupancy* occupancy) {
        return occupancy != nullptr && !occupancy->empty() ? occupancy : nullptr;
    }

    bool affordable() const {
        return texture_.instances.size() < o_.max_patches_per_lobe && texture_.triangles + min_cost_ <= o_.max_triangles;
    }

    bool reaches(int cell) const { return cell >= 0 && target_[cell] && filled_[cell] < layer_; }

    // Spread first: cells take one patch until the lobe is filled (or cannot be filled further);
    // then the docks that were dropped for it are taken up again, for a second patch per cell.
    // With a tight budget (big crowns) the patches reach more of the lobe before it runs out;
    // with a loose one the lobe ends as dense as before.
    Refill refill_queue(const DockingPoint& seed) {
        if (reseed(seed)) return Refill::Reseeded;
        if (!filled_enough() && fill_cursor_ < fill_order_.size()) return Refill::Again;  // a cell at the twig point itself
        if (layer_ >= kPatchesPerCell || deferred_.empty()) return Refill::Done;
        ++layer_;
        for (auto& pending : deferred_) queue_.push(std::move(pending));
        deferred_.clear();
        return Refill::Again;
    }

    bool filled_enough() const {
        return static_cast<double>(filled_count_) / fill_total_ >= o_.fill_target ||
               texture_.reseeds >= static_cast<std::size_t>(o_.max_reseeds_per_cell * fill_total_) || twigs_.empty();
    }

    // A new docking point on the placed twig nearest to the next empty target cell, pointing
    // into it; false when the lobe is filled enough or no empty cell is left.
    bool reseed(const DockingPoint& seed) {
        if (filled_enough()) return false;
        while (fill_cursor_ < fill_order_.size() && filled_[fill_order_[fill_cursor_]]) ++fill_cursor_;
        if (fill_cursor_ == fill_order_.size()) return false;
        const Eigen::Vector3f empty_cell = fill_grid_.cell_centre(fill_order_[fill_cursor_++]);
        const Eigen::Vector3f from = twigs_.point(twigs_.nearest(empty_cell));
        const Eigen::Vector3f dir = empty_cell - from;
        if (dir.norm() < 1e-5f) return false;
        // As thick as a twig must be to reach the empty cell, never thicker than the seed.
        const float thickness = std::clamp(dir.norm() / kPatchReach, 0.002f, std::max(seed.thickness, 0.002f));
        queue_.push({{from, dir.normalized(), thickness}, DockOrigin::Reseed, created_++});
        ++texture_.reseeds;
        return true;
    }

    // The best fit at a docking point. Seeds and re-seeds are placed whatever they fit, and their
    // thickness is not the lobe's: a re-seed is sized to reach its empty cell, and from a twig far
    // from it the patch grows so large that it sticks out of the lobe (straight twigs across a
    // palm's crown); a lobe's seed takes the skeleton's diameter at p_i, and on a palm's trunk top
    // its patch stood 2 m above the fronds. Both are also fitted at half the thickness, and half
    // again down to kMinRefitThickness, until a fit lies inside; the fit most inside is taken.
    Fit fit_at(const Pending& pending) {
        Fit best = fit_best(pending.dock, select_candidates(pending.dock));
        DockingPoint thinner = pending.dock;
        while (pending.forced() && best.inside_share < o_.min_inside_share && thinner.thickness > kMinRefitThickness) {
            thinner.thickness *= 0.5f;
            const Fit fit = fit_best(thinner, select_candidates(thinner));
            if (fit.inside_share > best.inside_share) best = fit;
        }
        return best;
    }

    // Patch selection: of the patches that fit the remaining budget, the candidates with the
    // smallest thickness/orientation mismatch, first in order_; returns their count.
    std::size_t select_candidates(const DockingPoint& d) {
        order_.clear();
        for (std::size_t i = 0; i < library_.patches.size(); ++i)
            if (texture_.triangles + cost_[i] <= o_.max_triangles) order_.push_back(static_cast<int>(i));
        const std::size_t count = std::min<std::size_t>(static_cast<std::size_t>(o_.candidates), order_.size());
        std::partial_sort(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(count), order_.end(), [&](int a, int b) {
            const float ca = mismatch(library_.patches[a], d), cb = mismatch(library_.patches[b], d);
            return ca != cb ? ca < cb : a < b;
        });
        return count;
    }

    // Patch fitting: geometry inside the lobe, plus lobe cells it newly reaches.
    Fit fit_best(const DockingPoint& d, std::size_t count) {
        double best_score = -1;
        Fit best;
        for (std::size_t c = 0; c < count; ++c) {
            PatchInstance inst = place(library_.patches[order_[c]], d, static_cast<float>(rng_.uniform(0, 2 * std::numbers::pi)));
            inst.patch = order_[c];
            const auto& s = fit_samples_[order_[c]];
            int inside = 0, reached = 0;
            for (const auto& sample : s) {
                const Eigen::Vector3f p = inst.apply(sample.position);
                inside += volume_.inside(p) ? 1 : 0;
                reached += reaches(fill_grid_.cell(p)) ? 1 : 0;
            }
            const double score = s.empty() ? 0.0 : (inside + 0.5 * reached) / static_cast<double>(s.size());
            if (score > best_score) {
                best_score = score;
                best = {inst, reached, s.empty() ? 0.0 : inside / static_cast<double>(s.size())};
            }
        }
        return best;
    }

    // The chosen patch joins the texture: its cells count as reached, its twig points can
    // re-seed, its docking points wait in the queue.
    void add(const PatchInstance& best) {
        texture_.instances.push_back(best);
        texture_.triangles += cost_[best.patch];
        ++texture_.docks_used;
        const Patch& patch = library_.patches[best.patch];
        for (const auto& sample : samples_[best.patch]) {
            const Eigen::Vector3f p = best.apply(sample.position);
            const int c = fill_grid_.cell(p);
            if (reaches(c) && filled_[c]++ == 0) ++filled_count_;
            if (sample.thickness > 0) twigs_.add(p);
        }
        for (const auto& dock : patch.docks)
            queue_.push({{best.apply(dock.position), best.rotation * dock.direction, dock.thickness * best.scale}, DockOrigin::Patch, created_++});
    }

    const PatchLibrary& library_;
    const TexturingOptions& o_;
    const LobeVolume volume_;
    const double cell_;
    const LobeVolume fill_grid_;
    const std::vector<char> target_;
    std::vector<int> filled_;  // patches reaching each cell
    int filled_count_ = 0;
    const int fill_total_;
    Rng rng_;
    std::vector<std::vector<Sample>> samples_, fit_samples_;
    GrowingKdTree twigs_;  // twig points of every placed patch (a scan over all of them made re-seeding quadratic)
    std::vector<int> fill_order_;
    std::size_t fill_cursor_ = 0;
    std::priority_queue<Pending, std::vector<Pending>, Later> queue_;
    std::size_t created_ = 0;
    std::vector<int> order_;
    int layer_ = 1;                  // patches a cell takes in the current pass
    std::vector<Pending> deferred_;  // docks dropped as redundant in an earlier pass
    std::vector<std::size_t> cost_;
    std::size_t min_cost_ = 0;
    LobeTexture texture_;
};

}  // namespace

LobeTexture texture_lobe(const TriangleMesh& lobe, const DockingPoint& seed, const PatchLibrary& library, const TexturingOptions& o,
                         std::uint64_t stream, const Occupancy* occupancy) {
    check_texturing(library, o);
    return LobeTexturer(lobe, library, o, stream, occupancy).run(seed);
}

}  // namespace treelobes::lobes
