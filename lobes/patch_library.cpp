#include "lobes/patch_library.hpp"

#include "core/error.hpp"
#include "core/random.hpp"
#include "geometry/polyline.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>
#include <numbers>
#include <utility>
#include <vector>

namespace treelobes::lobes {

namespace {

constexpr int kMaxChainsPerBranchlet = 60;    // thick chains first (breadth-first); bounds the library
constexpr float kLeafyThickness = 0.02f;      // leaves grow on twigs thinner than this (metres)
constexpr float kChildThicknessRatio = 0.6f;  // t' = ratio * #InitThickness * t at the fork

float radians(double degrees) { return static_cast<float>(degrees * std::numbers::pi / 180.0); }

// A unit vector perpendicular to v, turned by `spin` around v (the spiral angle).
Eigen::Vector3f perpendicular(const Eigen::Vector3f& v, float spin) {
    Eigen::Vector3f side = std::abs(v.z()) < 0.95f ? Eigen::Vector3f(v.cross(Eigen::Vector3f::UnitZ()))
                                                   : Eigen::Vector3f(v.cross(Eigen::Vector3f::UnitX()));
    side.normalize();
    return Eigen::AngleAxisf(spin, v) * side;
}

// v turned away from itself by `angle` toward the perpendicular at `spin`.
Eigen::Vector3f branch_off(const Eigen::Vector3f& v, float angle, float spin) {
    return (std::cos(angle) * v + std::sin(angle) * perpendicular(v, spin)).normalized();
}

bool distributed(const std::array<int, 2>& distr, int i) {
    const int period = std::max(1, distr[0] + distr[1]);
    return i % period < distr[0];
}

struct Seed {
    Eigen::Vector3f position;
    Eigen::Vector3f direction;
    float thickness;
};

// Douglas-Peucker on a chain's axis: the vertices that stay within `tolerance` of the chord of
// their span are dropped, the kept ones keep their thickness. The grown chain bends only by
// tropism and a little jitter, so most of its #ChainPts segments are nearly collinear and a
// patch needs a third or less of its prisms (the budget then buys more patches, lobes/synthesis.hpp).
std::vector<PatchSegment> simplify_axis(const std::vector<PatchSegment>& segments, float tolerance) {
    if (segments.size() < 2 || !(tolerance > 0)) return segments;
    std::vector<Eigen::Vector3f> points{segments.front().a};
    std::vector<float> thickness{segments.front().thickness_a};
    for (const auto& s : segments) {
        points.push_back(s.b);
        thickness.push_back(s.thickness_b);
    }
    const std::vector<char> keep = douglas_peucker(points.size(), tolerance, [&](std::size_t a, std::size_t b, std::size_t k) {
        return distance_to_segment(points[k], points[a], points[b]);
    });
    std::vector<PatchSegment> out;
    std::size_t last = 0;
    for (std::size_t k = 1; k < points.size(); ++k)
        if (keep[k]) {
            out.push_back({points[last], points[k], thickness[last], thickness[k]});
            last = k;
        }
    return out;
}

// Seed(t, v): one chain of #ChainPts segments with its leaves and new seeds (docking points).
Patch grow_chain(const Seed& seed, const SpeciesProfile& profile, const PatchLibraryOptions& o, Rng& rng, std::vector<Seed>& new_seeds) {
    const PatchProfile& pp = profile.patch;
    const LeafProfile& leaf = profile.growth.leaves;
    const Eigen::Vector3f up = Eigen::Vector3f::UnitZ();
    Patch patch;
    patch.root_thickness = seed.thickness;
    patch.root_direction = seed.direction;
    const int n = std::max(1, pp.chain_pts);
    const float step = static_cast<float>(o.segment_length) * seed.thickness;
    auto thickness_at = [&](int i) {  // #Allometric: how strongly the diameter falls along the axis
        return seed.thickness * static_cast<float>(std::pow(1.0 - 0.9 * i / n, pp.allometric));
    };
    Eigen::Vector3f p = Eigen::Vector3f::Zero(), v = seed.direction;
    float seed_spin = static_cast<float>(rng.uniform(0, 2 * std::numbers::pi));
    float leaf_spin = seed_spin;
    for (int i = 0; i < n; ++i) {
        const Eigen::Vector3f b = p + step * v;
        patch.segments.push_back({p, b, thickness_at(i), thickness_at(i + 1)});
        const float t = thickness_at(i + 1);
        // NewLeaf(v'): #LeafDistr nodes carry #NumLeaves leaves each.
        if (t <= kLeafyThickness && distributed(pp.leaf_distr, i) && leaf.per_branch > 0) {
            for (int k = 0; k < pp.num_leaves; ++k) {
                leaf_spin += radians(pp.leaf_spiral_angle);
                Eigen::Vector3f d = branch_off(v, radians(pp.leaf_angle), leaf_spin);
                d = (d + static_cast<float>(pp.leaf_phototropism - pp.leaf_gravitropism) * 0.5f * up).normalized();
                d = ((1.0f - static_cast<float>(pp.orient_up) * 0.3f) * d + static_cast<float>(pp.orient_up) * 0.3f * up).normalized();
                Eigen::Vector3f normal = d.cross(perpendicular(d, leaf_spin)).normalized();
                normal = ((1.0f - static_cast<float>(pp.face_up)) * normal + static_cast<float>(pp.face_up) * up);
                normal -= normal.dot(d) * d;
                if (normal.norm() < 1e-4f) normal = perpendicular(d, 0);
                const float size = static_cast<float>(1.0 + rng.uniform(-leaf.size_v, leaf.size_v));
                for (int c = 0; c < std::max(1, leaf.cluster); ++c)
                    patch.leaves.push_back(
                            {b, d, normal.normalized(), static_cast<float>(leaf.length_m) * size, static_cast<float>(leaf.width_m) * size});
            }
        }
        // Transf(v, #Phototropism, #Gravitropism), with a little random bending.
        // Drawn last coordinate first, in statements of their own: C++ leaves the order in which function
        // arguments are evaluated to the compiler (GCC right to left, Clang left to right), and this is the
        // order GCC gave the committed outputs.
        const auto jitter_z = static_cast<float>(rng.normal(0, 0.05));
        const auto jitter_y = static_cast<float>(rng.normal(0, 0.05));
        const auto jitter_x = static_cast<float>(rng.normal(0, 0.05));
        const Eigen::Vector3f jitter(jitter_x, jitter_y, jitter_z);
        v = (v + static_cast<float>(pp.phototropism - pp.gravitropism) / n * up + jitter).normalized();
        // NewSeed(t', v'): #BranchDistr nodes place #NumTwigs seeds if thick enough.
        const float child = kChildThicknessRatio * static_cast<float>(pp.init_thickness) * t;
        if (i + 1 < n && distributed(pp.branch_distr, i) && child >= o.min_twig_thickness) {
            for (int k = 0; k < pp.num_twigs; ++k) {
                seed_spin += radians(pp.spiral_angle);
                const Eigen::Vector3f d = branch_off(v, radians(pp.branching_angle), seed_spin);
                patch.docks.push_back({b, d, child});
                new_seeds.push_back({seed.position + b, d, child});
            }
        }
        p = b;
    }
    patch.step = step;
    patch.segments = simplify_axis(patch.segments, static_cast<float>(o.simplify_tolerance) * seed.thickness);
    // Random leaf order: a prefix of any length is an unbiased subsample (stochastic pruning).
    for (std::size_t i = patch.leaves.size(); i > 1; --i) std::swap(patch.leaves[i - 1], patch.leaves[rng.next() % i]);
    return patch;
}

}  // namespace

std::size_t kept_leaves(double fraction, std::size_t leaves) {
    return std::min(leaves, static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(leaves))));
}

std::size_t patch_triangles(const Patch& patch, int twig_sides, double leaf_share) {
    return 2 * static_cast<std::size_t>(twig_sides) * patch.segments.size() + 2 * kept_leaves(leaf_share, patch.leaves.size());
}

float Patch::length() const {
    float sum = 0;
    for (const auto& s : segments) sum += (s.b - s.a).norm();
    return sum;
}

PatchLibrary build_patch_library(const SpeciesProfile& profile, const PatchLibraryOptions& o) {
    if (o.branchlets < 1 || o.branchlets > 1000) throw Error::usage("patch library: branchlets must be 1..1000");
    if (!(o.min_root_thickness > 0 && o.max_root_thickness >= o.min_root_thickness && o.min_twig_thickness > 0 && o.segment_length > 0 &&
          o.simplify_tolerance >= 0))
        throw Error::usage("patch library: thicknesses and segment length must be positive (min <= max), the simplify tolerance >= 0");
    PatchLibrary library;
    library.species = profile.entry.name;
    library.leaf_shape = profile.growth.leaves.shape;
    library.leaf_cluster = profile.growth.leaves.cluster;
    library.branchlets = o.branchlets;
    for (int k = 0; k < o.branchlets; ++k) {
        Rng rng(o.seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(k) + 1);
        // Thickness log-spaced over the branchlets; elevation by a golden-ratio sequence from
        // slightly drooping (-15 deg) to vertical, so thickness and orientation vary independently.
        const double f = o.branchlets > 1 ? static_cast<double>(k) / (o.branchlets - 1) : 0.0;
        const float thickness = static_cast<float>(o.min_root_thickness * std::pow(o.max_root_thickness / o.min_root_thickness, f));
        const double golden = std::fmod(0.5 + k * 0.6180339887498949, 1.0);
        const float elevation = radians(-15.0 + 105.0 * golden);
        const Eigen::Vector3f direction(std::cos(elevation), 0.0f, std::sin(elevation));
        std::deque<Seed> queue{{Eigen::Vector3f::Zero(), direction, thickness}};
        int chains = 0;
        while (!queue.empty() && chains < kMaxChainsPerBranchlet) {
            const Seed seed = queue.front();
            queue.pop_front();
            std::vector<Seed> children;
            Patch patch = grow_chain(seed, profile, o, rng, children);
            patch.branchlet = k;
            library.patches.push_back(std::move(patch));
            ++chains;
            for (const auto& c : children) queue.push_back(c);
        }
    }
    return library;
}

}  // namespace treelobes::lobes
