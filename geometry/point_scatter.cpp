#include "geometry/point_scatter.hpp"

#include "core/error.hpp"

namespace treelobes {

PointScatter point_scatter(std::span<const Eigen::Vector3f> points, std::span<const int> indices) {
    if (indices.empty()) throw Error(ExitCode::Internal, "point_scatter: no points");
    PointScatter out;
    for (int i : indices) out.mean += points[static_cast<std::size_t>(i)].cast<double>();
    out.mean /= static_cast<double>(indices.size());
    for (int i : indices) {
        const Eigen::Vector3d d = points[static_cast<std::size_t>(i)].cast<double>() - out.mean;
        out.scatter += d * d.transpose();
    }
    return out;
}

}  // namespace treelobes
