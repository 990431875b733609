// Exact point-to-surface distances (CGAL AABB tree over the triangles; lobes/cgal_geometry.cpp).
// Used for the fidelity metrics of a synthesized tree: the one-sided distance from every input
// point to the synthesized mesh.
#pragma once

#include "core/point_cloud.hpp"
#include "core/triangle_mesh.hpp"

#include <memory>
#include <vector>

namespace treelobes::lobes {

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

}  // namespace treelobes::lobes
