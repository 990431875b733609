#include "synth/scene.hpp"

#include "core/error.hpp"
#include "core/random.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace treelobes::synth {

namespace {

// Smooth value noise in [-1, 1]: random values on an integer lattice, interpolated with a
// smoothstep. Lattice values come from hashed streams, so any point is reproducible alone.
double lattice(std::uint64_t seed, long long i, long long j) {
    const std::uint64_t key = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL ^ static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4FULL;
    return 2.0 * Rng(stream_seed(seed, key)).uniform() - 1.0;
}

double value_noise(std::uint64_t seed, double x, double y) {
    const double fx = std::floor(x), fy = std::floor(y);
    const auto i = static_cast<long long>(fx), j = static_cast<long long>(fy);
    const auto smooth = [](double t) { return t * t * (3.0 - 2.0 * t); };
    const double tx = smooth(x - fx), ty = smooth(y - fy);
    const double a = lattice(seed, i, j), b = lattice(seed, i + 1, j);
    const double c = lattice(seed, i, j + 1), d = lattice(seed, i + 1, j + 1);
    return (a + (b - a) * tx) * (1 - ty) + (c + (d - c) * tx) * ty;
}

}  // namespace

double Heightfield::height(double x, double y) const {
    const double gx = std::clamp((x - x0) / cell, 0.0, static_cast<double>(nx - 1));
    const double gy = std::clamp((y - y0) / cell, 0.0, static_cast<double>(ny - 1));
    const int i = std::min(static_cast<int>(gx), nx - 2), j = std::min(static_cast<int>(gy), ny - 2);
    const double tx = gx - i, ty = gy - j;
    return (at(i, j) * (1 - tx) + at(i + 1, j) * tx) * (1 - ty) + (at(i, j + 1) * (1 - tx) + at(i + 1, j + 1) * tx) * ty;
}

Heightfield make_ground(double x0, double y0, double x1, double y1, double slope_deg, double aspect_deg, double roughness_m,
                        std::uint64_t seed, double cell) {
    if (!(x1 > x0) || !(y1 > y0) || !(cell > 0)) throw Error::usage("ground extent must be non-empty");
    if (slope_deg < 0 || slope_deg > 45) throw Error::usage("ground slope " + std::to_string(slope_deg) + " is outside [0, 45] degrees");
    if (roughness_m < 0 || roughness_m > 10) throw Error::usage("ground roughness must be in [0, 10] m");
    Heightfield g;
    g.x0 = x0;
    g.y0 = y0;
    g.cell = cell;
    g.nx = static_cast<int>(std::ceil((x1 - x0) / cell)) + 1;
    g.ny = static_cast<int>(std::ceil((y1 - y0) / cell)) + 1;
    g.z.resize(static_cast<std::size_t>(g.nx) * g.ny);
    const double gradient = std::tan(slope_deg * std::numbers::pi / 180.0);
    const double ax = std::cos(aspect_deg * std::numbers::pi / 180.0), ay = std::sin(aspect_deg * std::numbers::pi / 180.0);
    const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    for (int j = 0; j < g.ny; ++j)
        for (int i = 0; i < g.nx; ++i) {
            const double x = x0 + i * cell, y = y0 + j * cell;
            // Downhill along the aspect; two octaves of noise (15 m hummocks, 3 m bumps).
            const double plane = -gradient * ((x - cx) * ax + (y - cy) * ay);
            const double noise = 0.8 * value_noise(seed, x / 15.0, y / 15.0) + 0.2 * value_noise(seed + 1, x / 3.0, y / 3.0);
            g.z[static_cast<std::size_t>(j) * g.nx + i] = static_cast<float>(plane + roughness_m * noise);
        }
    return g;
}

std::vector<Leaf> make_understory(const Heightfield& ground, int count, double max_height_m, std::uint64_t seed,
                                  const std::vector<Eigen::Vector2d>& avoid, double avoid_radius) {
    std::vector<Leaf> blades;
    Rng rng(stream_seed(seed, 0x5AB));
    const double x1 = ground.x0 + (ground.nx - 1) * ground.cell, y1 = ground.y0 + (ground.ny - 1) * ground.cell;
    for (int c = 0; c < count; ++c) {
        // Drawn last coordinate first, in statements of their own: C++ leaves the order in which function
        // arguments are evaluated to the compiler (GCC right to left, Clang left to right), and this is the
        // order GCC gave the committed outputs.
        const double centre_y = rng.uniform(ground.y0, y1);
        const double centre_x = rng.uniform(ground.x0, x1);
        Eigen::Vector2d centre(centre_x, centre_y);
        const bool blocked =
                std::any_of(avoid.begin(), avoid.end(), [&](const Eigen::Vector2d& a) { return (a - centre).norm() < avoid_radius; });
        if (blocked) continue;  // no bush inside a trunk
        const double height = rng.uniform(0.15, max_height_m);
        const double radius = rng.uniform(0.2, 0.4 + 0.6 * height);
        const int n = 15 + static_cast<int>(rng.below(static_cast<std::uint64_t>(20 + 60 * height)));
        for (int b = 0; b < n; ++b) {
            const double r = radius * std::sqrt(rng.uniform()), a = rng.uniform(0, 2 * std::numbers::pi);
            const double x = centre.x() + r * std::cos(a), y = centre.y() + r * std::sin(a);
            // Blades higher in the middle of the clump: a dome of foliage.
            const double top = height * (1.0 - 0.7 * (r / radius) * (r / radius));
            Leaf leaf;
            leaf.base = Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y),
                                        static_cast<float>(ground.height(x, y) + rng.uniform(0.0, top)));
            const double tilt = rng.uniform(0.2, 1.3), az = rng.uniform(0, 2 * std::numbers::pi);
            leaf.direction = Eigen::Vector3f(static_cast<float>(std::sin(tilt) * std::cos(az)),
                                             static_cast<float>(std::sin(tilt) * std::sin(az)), static_cast<float>(std::cos(tilt)));
            Eigen::Vector3f side = leaf.direction.cross(Eigen::Vector3f::UnitZ());
            if (side.norm() < 1e-4f) side = Eigen::Vector3f::UnitX();
            leaf.normal = side.cross(leaf.direction).normalized();
            leaf.length = static_cast<float>(rng.uniform(0.05, 0.18));
            leaf.width = static_cast<float>(leaf.length * rng.uniform(0.3, 0.6));
            leaf.internode = -1;
            blades.push_back(leaf);
        }
    }
    return blades;
}

Scene single_tree_scene(SyntheticTree tree, double margin_m, std::uint64_t seed) {
    if (!(margin_m >= 0 && margin_m <= 1000)) throw Error::usage("ground margin must be in [0, 1000] m");
    Scene scene;
    const double r = std::max(3.0, 0.5 * measure(tree).crown_diameter_m + margin_m);
    scene.ground = make_ground(-r, -r, r, r, 0.0, 0.0, 0.03, seed ^ 0x6D);
    scene.trees.push_back({std::move(tree), Eigen::Vector3d::Zero(), 1});
    return scene;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> Scene::bounds() const {
    const double inf = std::numeric_limits<double>::infinity();
    Eigen::Vector3d lo(inf, inf, inf), hi(-inf, -inf, -inf);
    const auto extend = [&](const Eigen::Vector3d& p) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    };
    for (const auto& placed : trees) {
        for (const auto& node : placed.tree.skeleton.nodes) {
            const Eigen::Vector3d p = placed.position + node.position.cast<double>();
            extend(p - Eigen::Vector3d::Constant(node.radius));
            extend(p + Eigen::Vector3d::Constant(node.radius));
        }
        for (const auto& leaf : placed.tree.leaves)
            for (const auto& c : leaf_corners(leaf, placed.tree.leaf_shape)) extend(placed.position + c.cast<double>());
    }
    if (ground) {
        const auto [zlo, zhi] = std::minmax_element(ground->z.begin(), ground->z.end());
        extend(Eigen::Vector3d(ground->x0, ground->y0, *zlo));
        extend(Eigen::Vector3d(ground->x0 + (ground->nx - 1) * ground->cell, ground->y0 + (ground->ny - 1) * ground->cell, *zhi));
    }
    for (const auto& leaf : understory)
        for (const auto& c : leaf_corners(leaf, understory_shape)) extend(c.cast<double>());
    for (const auto& m : meshes) {
        const Eigen::Vector3d offset = m.mesh.origin - origin;
        for (const auto& v : m.mesh.vertices) extend(offset + v.cast<double>());
    }
    if (lo.x() > hi.x()) throw Error::usage("the scene to scan is empty");
    return {lo, hi};
}

}  // namespace treelobes::synth
