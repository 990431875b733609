#include "render/tile_map.hpp"

#include "core/error.hpp"
#include "render/text.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_set>

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

std::vector<std::optional<LabelBox>> place_labels(int width, int height, std::span<const Eigen::Vector2i> marks, int mark_radius,
                                                  std::span<const Eigen::Vector2i> sizes) {
    if (sizes.size() != marks.size()) throw Error(ExitCode::Internal, "place_labels: one label size per mark expected");
    std::vector<std::uint8_t> taken(static_cast<std::size_t>(std::max(width, 0)) * static_cast<std::size_t>(std::max(height, 0)), 0);
    const auto mark_taken = [&](int x0, int y0, int x1, int y1) {  // inclusive corners, clipped to the image
        for (int y = std::max(y0, 0); y <= std::min(y1, height - 1); ++y)
            for (int x = std::max(x0, 0); x <= std::min(x1, width - 1); ++x) taken[static_cast<std::size_t>(y) * width + x] = 1;
    };
    const auto free = [&](const LabelBox& box) {
        if (box.x < 0 || box.y < 0 || box.x + box.width > width || box.y + box.height > height) return false;
        for (int y = box.y; y < box.y + box.height; ++y)
            for (int x = box.x; x < box.x + box.width; ++x)
                if (taken[static_cast<std::size_t>(y) * width + x]) return false;
        return true;
    };
    for (const auto& m : marks)
        mark_taken(m.x() - mark_radius - 1, m.y() - mark_radius - 1, m.x() + mark_radius + 1, m.y() + mark_radius + 1);
    std::vector<std::optional<LabelBox>> placed(marks.size());
    for (std::size_t i = 0; i < marks.size(); ++i) {
        const int w = sizes[i].x(), h = sizes[i].y(), x = marks[i].x(), y = marks[i].y(), gap = mark_radius + 3;
        for (const LabelBox& box : {LabelBox{x + gap, y - h / 2, w, h}, LabelBox{x - gap - w, y - h / 2, w, h},
                                    LabelBox{x - w / 2, y - gap - h, w, h}, LabelBox{x - w / 2, y + gap, w, h}}) {
            if (!free(box)) continue;
            placed[i] = box;
            // A few pixels around the box stay free, so that two ids never read as one number.
            mark_taken(box.x - 3, box.y - 3, box.x + box.width + 2, box.y + box.height + 2);
            break;
        }
    }
    return placed;
}

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
    std::unordered_set<int> not_trees;
    for (const auto& stem : stems)
        if (stem.not_a_tree) not_trees.insert(stem.id);
    Image image(width, height, {255, 255, 255, 255});
    for (std::size_t cell = 0; cell < owner.size(); ++cell) {
        const std::size_t i = owner[cell];
        if (i == cloud.size()) continue;
        const float h = height_above_ground.empty() ? cloud.positions[i].z() : height_above_ground[i];
        const double light = 0.55 + 0.45 * (h - lowest) / span;  // higher is brighter
        const int x = static_cast<int>(cell % width), y = static_cast<int>(cell / width);
        Rgba colour = tree_id[i] <= 0                  ? Rgba{170, 170, 165, 255}
                      : not_trees.contains(tree_id[i]) ? ((x + y) / 3 % 2 ? Rgba{235, 235, 240, 255} : Rgba{90, 90, 105, 255})
                                                       : tree_colour(tree_id[i]);
        for (int c = 0; c < 3; ++c) colour[c] = static_cast<std::uint8_t>(colour[c] * light);
        image.set(x, y, colour);
    }
    const int mark = std::clamp(width / 160, 3, 8), scale = std::clamp(width / 250, 2, 5);
    std::vector<Eigen::Vector2i> marks, sizes;
    for (const auto& stem : stems) {
        marks.emplace_back(column(stem.position.x()), row(stem.position.y()));
        // The box holds the text and a one-pixel white border.
        sizes.emplace_back(text_width(std::to_string(stem.id), scale) + 2, text_height(scale) + 2);
        draw_disc(image, marks.back().x(), marks.back().y(), mark + 1, {255, 255, 255, 255});
        draw_disc(image, marks.back().x(), marks.back().y(), mark, {0, 0, 0, 255});
        if (stem.not_a_tree) draw_disc(image, marks.back().x(), marks.back().y(), mark / 2, {255, 255, 255, 255});  // a ring
    }
    if (!options.labels) return image;
    const auto boxes = place_labels(width, height, marks, mark + 1, sizes);
    for (std::size_t i = 0; i < stems.size(); ++i) {
        if (!boxes[i]) continue;
        const LabelBox& box = *boxes[i];
        image.fill_rect(box.x, box.y, box.x + box.width, box.y + box.height, {255, 255, 255, 255});
        draw_text(image, box.x + 1, box.y + 1, std::to_string(stems[i].id), scale, {0, 0, 0, 255});
    }
    return image;
}

}  // namespace treelobes::render
