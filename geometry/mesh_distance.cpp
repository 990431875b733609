#include "geometry/mesh_distance.hpp"

#include <algorithm>
#include <numeric>

namespace treelobes {

DistanceSummary summarise_distances(std::vector<float> distances) {
    DistanceSummary s;
    s.count = distances.size();
    if (distances.empty()) return s;
    std::sort(distances.begin(), distances.end());
    const auto at = [&](double q) {
        return static_cast<double>(distances[static_cast<std::size_t>(q * static_cast<double>(distances.size() - 1) + 0.5)]);
    };
    s.mean = std::accumulate(distances.begin(), distances.end(), 0.0) / static_cast<double>(distances.size());
    s.median = at(0.5);
    s.p95 = at(0.95);
    s.max = distances.back();
    return s;
}

}  // namespace treelobes
