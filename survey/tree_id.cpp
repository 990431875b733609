#include "survey/tree_id.hpp"

#include "core/error.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numeric>
#include <algorithm>

namespace treelobes::survey {

namespace {

constexpr double kTenthsOfMillimetrePerMetre = 1e4;
constexpr std::int64_t kTenthsOfMillimetrePerCentimetre = 100;

// floor(x / 1 cm) in whole centimetres, from x rounded to 0.1 mm.
std::int64_t centimetre_cell(double metres) {
    const double tenths = std::round(metres * kTenthsOfMillimetrePerMetre);
    if (!std::isfinite(tenths) || std::abs(tenths) > 9e15)
        throw Error::input("",
                           "stem base coordinate " + std::to_string(metres) + " is out of range for a tree id (CRS units must be metres)");
    const auto t = static_cast<std::int64_t>(tenths);
    const std::int64_t q = t / kTenthsOfMillimetrePerCentimetre;
    return (t % kTenthsOfMillimetrePerCentimetre < 0) ? q - 1 : q;
}

std::string metres_text(std::int64_t centimetres) {
    char text[32];
    const std::int64_t magnitude = std::llabs(centimetres);
    std::snprintf(text, sizeof text, "%s%lld.%02lld", centimetres < 0 ? "-" : "", static_cast<long long>(magnitude / 100),
                  static_cast<long long>(magnitude % 100));
    return text;
}

}  // namespace

std::string stable_tree_id(double x, double y) { return metres_text(centimetre_cell(x)) + "_" + metres_text(centimetre_cell(y)); }

std::vector<std::string> stable_tree_ids(const std::vector<Eigen::Vector3d>& bases) {
    std::vector<std::size_t> order(bases.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return bases[a].z() < bases[b].z(); });
    std::vector<std::string> ids(bases.size());
    std::map<std::string, int> seen;
    for (std::size_t i : order) {
        const std::string id = stable_tree_id(bases[i].x(), bases[i].y());
        const int count = ++seen[id];
        ids[i] = count == 1 ? id : id + "~" + std::to_string(count);
    }
    return ids;
}

}  // namespace treelobes::survey
