// Grid thinning: keep the first point (in input order) of every cell of a cubic grid. Used where
// a stage needs a bounded, density-independent subset of a cloud (alpha shapes of big clusters,
// hull features, comparing simulated scans with grid-thinned real ones). Input order decides
// which point stands for a cell, so the result is deterministic.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <unordered_set>
#include <vector>

namespace treelobes {

// Indices of the kept points. Cells are `cell` wide and anchored at `anchor`; cell indices are
// taken modulo 2^21 per axis (ample for a tree or a tile at centimetre cells).
template <typename Scalar>
std::vector<std::size_t> first_point_per_cell(const std::vector<Eigen::Matrix<Scalar, 3, 1>>& points, Scalar cell,
                                              const Eigen::Matrix<Scalar, 3, 1>& anchor = Eigen::Matrix<Scalar, 3, 1>::Zero()) {
    const auto index = [cell](Scalar v) { return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v / cell)) & 0x1FFFFF); };
    std::unordered_set<std::uint64_t> seen;
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Matrix<Scalar, 3, 1> p = points[i] - anchor;
        const std::uint64_t key = index(p.x()) | index(p.y()) << 21 | index(p.z()) << 42;
        if (seen.insert(key).second) kept.push_back(i);
    }
    return kept;
}

}  // namespace treelobes
