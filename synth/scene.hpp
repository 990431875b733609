// What a simulated scanner sees: placed synthetic trees, a ground surface and low vegetation,
// all in one local frame (metres) with a double-precision origin for georeferenced output.
#pragma once

#include "core/triangle_mesh.hpp"
#include "synth/grow.hpp"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace treelobes::synth {

struct PlacedTree {
    SyntheticTree tree;                 // tree-local coordinates, stem base at (0,0,0)
    Eigen::Vector3d position{0, 0, 0};  // stem base in the scene frame
    int tree_id = 1;                    // 1-based label; 0 means "no tree"
};

// Ground as a regular grid of heights, triangulated two triangles per cell.
struct Heightfield {
    double x0 = 0, y0 = 0;  // corner of the grid (scene frame)
    double cell = 1.0;      // grid spacing (metres)
    int nx = 0, ny = 0;     // samples along x and y
    std::vector<float> z;   // nx * ny heights, row by row (y major)

    float at(int i, int j) const { return z[static_cast<std::size_t>(j) * nx + i]; }
    // Bilinear height at (x, y), clamped to the grid.
    double height(double x, double y) const;
};

// A gently sloping, slightly rough ground over [x0, x1] x [y0, y1]: plane with the given
// slope (degrees, direction `aspect_deg` downhill) plus value noise of `roughness_m` amplitude.
Heightfield make_ground(double x0, double y0, double x1, double y1, double slope_deg, double aspect_deg, double roughness_m,
                        std::uint64_t seed, double cell = 0.5);

// A triangle mesh in the scene, such as a CG tree model to be scanned (synth/mesh_sampling.hpp):
// its vertices are placed at mesh.origin + vertex in world coordinates; wood[f] is 1 for a
// bark face and 0 for a leaf face.
struct SceneMesh {
    TriangleMesh mesh;
    std::vector<std::uint8_t> wood;
};

struct Scene {
    Eigen::Vector3d origin{0, 0, 0};  // added to every output position
    std::vector<PlacedTree> trees;
    std::optional<Heightfield> ground;  // class 2
    std::vector<Leaf> understory;       // low vegetation blades in the scene frame (class 3)
    LeafShape understory_shape = LeafShape::Broad;
    std::vector<SceneMesh> meshes;  // class 5 (tree), labelled wood/leaf per face, tree id 0

    // Bounding box of everything in the scene frame.
    std::pair<Eigen::Vector3d, Eigen::Vector3d> bounds() const;
};

// One tree at the origin on a flat, slightly rough patch of ground reaching `margin_m` beyond
// its crown (like a single-tree scan clipped from a plot), tree id 1.
Scene single_tree_scene(SyntheticTree tree, double margin_m, std::uint64_t seed);

// Bushes and grass tufts: `count` clumps of blades standing on the ground, up to `max_height_m`.
std::vector<Leaf> make_understory(const Heightfield& ground, int count, double max_height_m, std::uint64_t seed,
                                  const std::vector<Eigen::Vector2d>& avoid = {}, double avoid_radius = 0.0);

}  // namespace treelobes::synth
