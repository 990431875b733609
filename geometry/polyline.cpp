#include "geometry/polyline.hpp"

#include <algorithm>
#include <utility>

namespace treelobes {

float distance_to_segment(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const Eigen::Vector3f chord = b - a, d = p - a;
    const float length2 = chord.squaredNorm();
    const float along = length2 > 0 ? std::clamp(d.dot(chord) / length2, 0.0f, 1.0f) : 0.0f;
    return (d - along * chord).norm();
}

std::vector<char> douglas_peucker(std::size_t n, float tolerance,
                                  const std::function<float(std::size_t a, std::size_t b, std::size_t k)>& deviation) {
    std::vector<char> keep(n, 0);
    if (n == 0) return keep;
    keep.front() = keep.back() = 1;
    std::vector<std::pair<std::size_t, std::size_t>> spans{{0, n - 1}};
    while (!spans.empty()) {
        const auto [a, b] = spans.back();
        spans.pop_back();
        float worst = 0;
        std::size_t at = a;
        for (std::size_t k = a + 1; k < b; ++k)
            if (const float off = deviation(a, b, k); off > worst) {
                worst = off;
                at = k;
            }
        if (!(worst > tolerance)) continue;
        keep[at] = 1;
        spans.push_back({at, b});
        spans.push_back({a, at});
    }
    return keep;
}

}  // namespace treelobes
