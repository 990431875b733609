// TriangleMesh: an indexed triangle mesh in local coordinates plus a double origin.
// OpenMesh is used for file IO only (core/mesh_io.cpp); stages pass this plain type.
#pragma once

#include <Eigen/Core>

#include <array>
#include <vector>

namespace treelobes {

struct TriangleMesh {
    Eigen::Vector3d origin{0, 0, 0};
    std::vector<Eigen::Vector3f> vertices;
    std::vector<std::array<int, 3>> faces;  // counter-clockwise seen from outside

    std::size_t vertex_count() const { return vertices.size(); }
    std::size_t face_count() const { return faces.size(); }

    // Appends another mesh (its origin is converted into this mesh's frame).
    void append(const TriangleMesh& other);
    // Signed volume (positive for a closed, outward-oriented mesh) and surface area.
    double signed_volume() const;
    double area() const;
    // Area-weighted vertex normals, unit length; zero for a vertex no face uses.
    std::vector<Eigen::Vector3f> vertex_normals() const;
};

}  // namespace treelobes
