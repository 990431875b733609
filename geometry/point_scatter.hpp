// Mean and scatter matrix of a subset of points: the neighbourhood shape behind the
// preprocessing's leafy-crown gate, the neighbour graph's piece axes and classification's hull
// features.
#pragma once

#include <Eigen/Core>

#include <span>

namespace treelobes {

// Mean and scatter matrix sum (p - mean)(p - mean)^T (not divided by the count; in double) of
// the points at `indices`: the principal directions and shape of a neighbourhood or a piece of a
// cloud come from its eigen-decomposition. Throws Error(Internal) for empty `indices`.
struct PointScatter {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
};
PointScatter point_scatter(std::span<const Eigen::Vector3f> points, std::span<const int> indices);

}  // namespace treelobes
