#include "core/triangle_mesh.hpp"

#include <Eigen/Geometry>

namespace treelobes {

void TriangleMesh::append(const TriangleMesh& other) {
    const int base = static_cast<int>(vertices.size());
    if (vertices.empty() && faces.empty()) origin = other.origin;  // adopt the frame of the first part
    const Eigen::Vector3f offset = (other.origin - origin).cast<float>();
    for (const auto& v : other.vertices) vertices.push_back(v + offset);
    for (const auto& f : other.faces) faces.push_back({f[0] + base, f[1] + base, f[2] + base});
}

double TriangleMesh::signed_volume() const {
    double volume = 0.0;
    for (const auto& f : faces) {
        const Eigen::Vector3d a = vertices[f[0]].cast<double>(), b = vertices[f[1]].cast<double>(), c = vertices[f[2]].cast<double>();
        volume += a.dot(b.cross(c)) / 6.0;
    }
    return volume;
}

double TriangleMesh::area() const {
    double sum = 0.0;
    for (const auto& f : faces) {
        const Eigen::Vector3d a = vertices[f[0]].cast<double>(), b = vertices[f[1]].cast<double>(), c = vertices[f[2]].cast<double>();
        sum += 0.5 * (b - a).cross(c - a).norm();
    }
    return sum;
}

std::vector<Eigen::Vector3f> TriangleMesh::vertex_normals() const {
    std::vector<Eigen::Vector3f> normals(vertices.size(), Eigen::Vector3f::Zero());
    for (const auto& f : faces) {
        const Eigen::Vector3f n = (vertices[f[1]] - vertices[f[0]]).cross(vertices[f[2]] - vertices[f[0]]);
        for (int v : f) normals[v] += n;
    }
    for (auto& n : normals) n.normalize();  // Eigen leaves a zero vector as it is
    return normals;
}

}  // namespace treelobes
