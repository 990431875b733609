// Exact point-to-surface distances (CGAL AABB tree over the triangles; geometry/cgal_surfaces.cpp).
// Used for the fidelity metrics of a synthesized tree: the one-sided distance from every input
// point to the synthesized mesh.
#pragma once

#include "core/point_cloud.hpp"
#include "core/triangle_mesh.hpp"

#include <memory>
#include <vector>

namespace treelobes {

// Mean, median, 95th percentile and maximum of a list of distances (all 0 for an empty list):
// one direction of a Metro-style surface comparison (Cignoni et al. 1998), whose maximum is
// that direction's Hausdorff distance.
struct DistanceSummary {
    std::size_t count = 0;
    double mean = 0, median = 0, p95 = 0, max = 0;
};
DistanceSummary summarise_distances(std::vector<float> distances);

class MeshDistance {
public:
    explicit MeshDistance(const TriangleMesh& mesh);  // Error(Usage) for a mesh without faces
    ~MeshDistance();
    MeshDistance(const MeshDistance&) = delete;
    MeshDistance& operator=(const MeshDistance&) = delete;

    // Distance from a point given in the mesh's local frame.
    double distance(const Eigen::Vector3d& local) const;
    // Distance of every point of `cloud` (its origin is honoured); parallel (TBB).
    std::vector<float> distances(const PointCloud& cloud) const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    Eigen::Vector3d origin_;
};

}  // namespace treelobes
