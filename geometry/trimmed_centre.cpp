#include "geometry/trimmed_centre.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <limits>
#include <vector>

namespace treelobes {

namespace {

// Mean x, y of the points whose squared horizontal distance to `centre` is at most `limit`.
Eigen::Vector2d mean_xy_within(std::span<const Eigen::Vector3f> points, const Eigen::Vector2d& centre, double limit) {
    Eigen::Vector2d sum(0, 0);
    std::size_t count = 0;
    for (const Eigen::Vector3f& p : points)
        if ((p.head<2>().cast<double>() - centre).squaredNorm() <= limit) {
            sum += p.head<2>().cast<double>();
            ++count;
        }
    return sum / static_cast<double>(count);
}

}  // namespace

Eigen::Vector2d trimmed_centre_xy(std::span<const Eigen::Vector3f> points, const TrimmedCentreOptions& options) {
    if (points.empty()) throw Error(ExitCode::Internal, "trimmed_centre_xy: no points");
    if (!(options.keep > 0 && options.keep <= 1)) throw Error::usage("trimmed centre: keep must be in (0, 1]");
    if (options.rounds < 0) throw Error::usage("trimmed centre: rounds must not be negative");
    Eigen::Vector2d centre = mean_xy_within(points, Eigen::Vector2d::Zero(), std::numeric_limits<double>::infinity());
    if (options.keep == 1) return centre;
    std::vector<double> squared(points.size());
    const auto rank = static_cast<std::ptrdiff_t>(options.keep * static_cast<double>(points.size() - 1));
    for (int round = 0; round < options.rounds; ++round) {
        for (std::size_t i = 0; i < points.size(); ++i) squared[i] = (points[i].head<2>().cast<double>() - centre).squaredNorm();
        std::nth_element(squared.begin(), squared.begin() + rank, squared.end());
        centre = mean_xy_within(points, centre, squared[static_cast<std::size_t>(rank)]);
    }
    return centre;
}

}  // namespace treelobes
