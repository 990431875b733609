// Polyline simplification: Douglas–Peucker (D. Douglas, T. Peucker, *Algorithms for the reduction
// of the number of points required to represent a digitized line or its caricature*, 1973). The
// synthesized patches' chain axes and the main skeleton a .tlobe stores both keep only the
// points that bend their chain.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <vector>

namespace treelobes {

// Distance from p to the segment a-b (to a when a == b).
float distance_to_segment(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b);

// Which of the n points of an open chain to keep (1) so that every dropped point k lies within
// `tolerance` of the span (a, b) of kept points around it: deviation(a, b, k) <= tolerance,
// a < k < b. Both ends are kept. The span's worst point is kept first, so running the
// simplification again on the kept points keeps them all.
std::vector<char> douglas_peucker(std::size_t n, float tolerance,
                                  const std::function<float(std::size_t a, std::size_t b, std::size_t k)>& deviation);

}  // namespace treelobes
