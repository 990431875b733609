#include "render/tile_map.hpp"

#include "core/error.hpp"
#include "render/text.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace treelobes::render {

namespace {

Rgba hsv(double hue, double saturation, double value) {
    const double h = std::fmod(hue, 1.0) * 6.0;
    const int sector = static_cast<int>(h);
    const double f = h - sector, p = value * (1 - saturation), q = value * (1 - saturation * f), t = value * (1 - saturation * (1 - f));
    double r = value, g = t, b = p;
    switch (sector) {
        case 1:
            r = q, g = value, b = p;
            break;
        case 2:
            r = p, g = value, b = t;
            break;
        case 3:
            r = p, g = q, b = value;
            break;
        case 4:
            r = t, g = p, b = value;
            break;
        case 5:
            r = value, g = p, b = q;
            break;
        default:
            break;
    }
    auto byte = [](double v) { return static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5); };
    return {byte(r), byte(g), byte(b), 255};
}

void draw_disc(Image& image, int cx, int cy, int radius, Rgba colour) {
    for (int y = -radius; y <= radius; ++y)
        for (int x = -radius; x <= radius; ++x)
            if (x * x + y * y <= radius * radius) image.set(cx + x, cy + y, colour);
}

}  // namespace

Rgba tree_colour(int id) {
    // Golden-ratio steps around the hue circle; three brightness levels break up equal hues.
    const double hue = std::fmod(0.61803398875 * static_cast<double>(id), 1.0);
    return hsv(hue, 0.75, 0.95 - 0.12 * (id % 3));
}

Image draw_tile_map(const PointCloud& cloud, std::span<const int> tree_id, std::span<const float> height_above_ground,
                    std::span<const TileMapStem> stems, const TileMapOptions& options) {
    if (cloud.empty()) throw Error(ExitCode::Internal, "draw_tile_map: empty cloud");
    if (tree_id.size() != cloud.size() || (!height_above_ground.empty() && height_above_ground.size() != cloud.size()))
        throw Error(ExitCode::Internal, "draw_tile_map: one tree id and height per point expected");
    const auto bounds = cloud.bounds();  // not a structured binding: clang 14 cannot capture those in lambdas
    const auto& lo = bounds.first;
    const auto& hi = bounds.second;
    const double extent = std::max({static_cast<double>(hi.x() - lo.x()), static_cast<double>(hi.y() - lo.y()), 1e-3});
    const double pixel = std::max(options.min_pixel_m, extent / options.max_side_px);
    const int m = options.margin_px;
    const int width = static_cast<int>(std::ceil((hi.x() - lo.x()) / pixel)) + 1 + 2 * m;
    const int height = static_cast<int>(std::ceil((hi.y() - lo.y()) / pixel)) + 1 + 2 * m;
    auto column = [&](double x) { return m + static_cast<int>((x - lo.x()) / pixel); };
    auto row = [&](double y) { return height - 1 - m - static_cast<int>((y - lo.y()) / pixel); };  // north up

    // Highest point per pixel decides its colour (the view from above). A sparse (airborne) scan
    // leaves most pixels empty, so each point covers a disc about as wide as the mean point
    // spacing over the tile's footprint.
    const double area = std::max(static_cast<double>(hi.x() - lo.x()) * (hi.y() - lo.y()), pixel * pixel);
    const double spacing = std::sqrt(area / static_cast<double>(cloud.size()));
    const int splat = std::min(12, static_cast<int>(std::ceil(0.75 * spacing / pixel)) - 1);
    std::vector<float> top(static_cast<std::size_t>(width) * height, -std::numeric_limits<float>::infinity());
    std::vector<std::size_t> owner(top.size(), cloud.size());
    float lowest = std::numeric_limits<float>::infinity(), highest = -lowest;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float h = height_above_ground.empty() ? cloud.positions[i].z() : height_above_ground[i];
        lowest = std::min(lowest, h);
        highest = std::max(highest, h);
        const int cx = column(cloud.positions[i].x()), cy = row(cloud.positions[i].y());
        for (int dy = -splat; dy <= splat; ++dy)
            for (int dx = -splat; dx <= splat; ++dx) {
                const int x = cx + dx, y = cy + dy;
                if (dx * dx + dy * dy > splat * splat || x < 0 || y < 0 || x >= width || y >= height) continue;
                const std::size_t cell = static_cast<std::size_t>(y) * width + x;
                if (cloud.positions[i].z() > top[cell]) {
                    top[cell] = cloud.positions[i].z();
                    owner[cell] = i;
                }
            }
    }
    const float span = std::max(highest - lowest, 1e-3f);
    Image image(width, height, {255, 255, 255, 255});
    for (std::size_t cell = 0; cell < owner.size(); ++cell) {
        const std::size_t i = owner[cell];
        if (i == cloud.size()) continue;
        const float h = height_above_ground.empty() ? cloud.positions[i].z() : height_above_ground[i];
        const double light = 0.55 + 0.45 * (h - lowest) / span;  // higher is brighter
        Rgba colour = tree_id[i] > 0 ? tree_colour(tree_id[i]) : Rgba{170, 170, 165, 255};
        for (int c = 0; c < 3; ++c) colour[c] = static_cast<std::uint8_t>(colour[c] * light);
        image.set(static_cast<int>(cell % width), static_cast<int>(cell / width), colour);
    }
    const int mark = std::clamp(width / 160, 3, 8), scale = std::clamp(width / 250, 2, 5);
    for (const auto& stem : stems) {
        const int x = column(stem.position.x()), y = row(stem.position.y());
        draw_disc(image, x, y, mark + 1, {255, 255, 255, 255});
        draw_disc(image, x, y, mark, {0, 0, 0, 255});
        if (!options.labels) continue;
        const std::string label = std::to_string(stem.id);
        const int tx = x + mark + 3, ty = y - text_height(scale) / 2;
        image.fill_rect(tx - 1, ty - 1, tx + text_width(label, scale), ty + text_height(scale) + 1, {255, 255, 255, 255});
        draw_text(image, tx, ty, label, scale, {0, 0, 0, 255});
    }
    return image;
}

}  // namespace treelobes::render
