#include "render/colour_map.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace treelobes::render {

Rgba ramp_colour(double t) {
    // Five stops of matplotlib's viridis (van der Walt and Smith 2015), linearly interpolated.
    static constexpr std::array<std::array<double, 3>, 5> stops = {
            {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}}};
    t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
    const double x = t * (stops.size() - 1);
    const std::size_t i = std::min(stops.size() - 2, static_cast<std::size_t>(x));
    const double f = x - static_cast<double>(i);
    Rgba c{0, 0, 0, 255};
    for (int k = 0; k < 3; ++k) c[k] = static_cast<std::uint8_t>(std::lround(stops[i][k] + f * (stops[i + 1][k] - stops[i][k])));
    return c;
}

Rgba id_colour(long long id) {
    if (id == 0) return {170, 170, 170, 255};
    const double hue = std::fmod(static_cast<double>(id) * 137.50776405, 360.0) / 60.0;  // golden angle, in sextants
    const double fraction = hue - std::floor(hue);
    const double v = 0.9, s = 0.75;
    const double p = v * (1 - s), q = v * (1 - s * fraction), u = v * (1 - s * (1 - fraction));
    std::array<double, 3> rgb{};
    switch (static_cast<int>(hue) % 6) {
        case 0:
            rgb = {v, u, p};
            break;
        case 1:
            rgb = {q, v, p};
            break;
        case 2:
            rgb = {p, v, u};
            break;
        case 3:
            rgb = {p, q, v};
            break;
        case 4:
            rgb = {u, p, v};
            break;
        default:
            rgb = {v, p, q};
            break;
    }
    return {static_cast<std::uint8_t>(rgb[0] * 255), static_cast<std::uint8_t>(rgb[1] * 255), static_cast<std::uint8_t>(rgb[2] * 255), 255};
}

}  // namespace treelobes::render
