#include "render/leaf_texture.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace treelobes::render {

namespace {

// Half width of the blade (fraction of the image) at height t along it (0 = base, 1 = tip):
// widest a third of the way up, round at the base, pointed at the tip.
double blade_half_width(double t) {
    if (t <= 0 || t >= 1) return 0;
    return 0.40 * std::pow(std::sin(M_PI * std::pow(t, 0.75)), 0.9);
}

std::uint8_t channel(double v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0))); }

}  // namespace

Image leaf_texture(int size) {
    if (size < 8 || size > 4096) throw Error::usage("leaf texture size must be 8..4096 pixels");
    Image image(size, size, {0, 0, 0, 0});
    constexpr double blade_base = 0.12, stalk_half_width = 0.025;  // petiole below blade_base (image fractions)
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double u = (x + 0.5) / size - 0.5;                  // -0.5 .. 0.5 across
            const double h = 1.0 - (y + 0.5) / size;                  // 0 at the bottom row, 1 at the top
            const double t = (h - blade_base) / (0.98 - blade_base);  // along the blade
            const double half = blade_half_width(t);
            if (h < blade_base + 0.02 && std::abs(u) < stalk_half_width && h > 0.01) {
                image.set(x, y, {70, 100, 35, 255});  // petiole
                continue;
            }
            if (std::abs(u) >= half) continue;
            const double across = std::abs(u) / half;  // 0 at the midrib, 1 at the margin
            // Side veins leave the midrib at 45 degrees upward, 6 pairs along the blade.
            const double vein_phase = std::fmod(t * 6.0 + across * half * 6.0 / 0.4 * 0.7 + 10.0, 1.0);
            const bool midrib = std::abs(u) < 0.012 + 0.01 * (1 - t);
            const bool vein = vein_phase < 0.08 && across < 0.85;
            double r = 58 + 30 * t, g = 128 + 25 * t, b = 40;
            const double shade = 1.0 - 0.35 * across * across;  // darker toward the margin
            r *= shade, g *= shade, b *= shade;
            if (midrib || vein) r += 45, g += 45, b += 25;
            image.set(x, y, {channel(r), channel(g), channel(b), 255});
        }
    return image;
}

}  // namespace treelobes::render
