// Ray casting against a synth::Scene with Intel Embree 3 (kept inside ray_scene.cpp).
// Branches are traced as Embree linear curves, one segment per internode with the true radii at
// both ends (exact tubes, no tessellation; round joints, steep root flares as plain cones),
// leaves as quads, the ground and scene meshes (CG tree models, labelled wood/leaf per face) as
// triangles; every hit says which tree, which internode and what kind of surface it struck.
#pragma once

#include "synth/scene.hpp"

#include <Eigen/Core>

#include <memory>

namespace treelobes::synth {

enum class Surface : std::uint8_t { Wood, Leaf, Ground, Understory };

struct RayHit {
    float t = 0;                      // distance along the (unit) ray direction
    Eigen::Vector3f normal{0, 0, 1};  // unit geometric normal
    Surface surface = Surface::Ground;
    int tree = -1;       // index into Scene::trees, -1 for ground and understory
    int internode = -1;  // skeleton node whose internode was hit (leaves: their carrier)
    float reflectance = 0.3f;
};

class RayScene {
public:
    explicit RayScene(const Scene& scene);
    ~RayScene();
    RayScene(const RayScene&) = delete;
    RayScene& operator=(const RayScene&) = delete;

    // Closest hit along origin + t * direction (direction unit length) for t in [t_near, t_far].
    // Thread-safe: scans call it from many threads at once.
    bool intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_near, float t_far, RayHit& hit) const;

    std::size_t primitive_count() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace treelobes::synth
