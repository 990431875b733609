// Small synthetic tiles with known ground and trees for the segment tests.
#pragma once

#include "core/point_cloud.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

namespace treelobes::test {

// A cloud plus the true tree id of every point (0 = ground or no tree).
struct ToyTile {
    PointCloud cloud;
    std::vector<std::int32_t> truth;
    void add(const Eigen::Vector3f& p, std::int32_t tree) {
        cloud.positions.push_back(p);
        truth.push_back(tree);
    }
};

// Rough inclined ground: a plane rising `slope_deg` along x with a smooth bump pattern.
inline float ground_height(float x, float y, float slope_deg, float roughness) {
    return std::tan(slope_deg * std::numbers::pi_v<float> / 180.0f) * x + roughness * std::sin(0.6f * x) * std::cos(0.5f * y);
}

// Ground points on a square grid over [x0, x1] x [y0, y1]; `skip` leaves a hole (no returns).
template <typename Skip>
void add_ground(ToyTile& tile, float x0, float x1, float y0, float y1, float spacing, float slope_deg, float roughness, Skip skip) {
    for (float y = y0; y <= y1; y += spacing)
        for (float x = x0; x <= x1; x += spacing)
            if (!skip(x, y)) tile.add({x, y, ground_height(x, y, slope_deg, roughness)}, 0);
}

// A tile of flat ground at z = 0 over [x0, x1] x [y0, y1], a return every 5 cm (a terrestrial
// scan's density), to put trees on.
inline ToyTile flat_ground(float x0, float x1, float y0, float y1) {
    ToyTile tile;
    add_ground(tile, x0, x1, y0, y1, 0.05f, 0.0f, 0.0f, [](float, float) { return false; });
    return tile;
}

// Classes as a classified tile has them: every point that is no tree's is ground (2), the rest
// unclassified (1).
inline void classify_ground(ToyTile& tile) {
    tile.cloud.classification.assign(tile.cloud.size(), 1);
    for (std::size_t i = 0; i < tile.cloud.size(); ++i)
        if (!tile.truth[i]) tile.cloud.classification[i] = 2;
}

// The same for a tile on flat ground at z = 0 that holds other points than trees (a bush): only
// the points at z = 0 are ground.
inline void classify_flat_ground(ToyTile& tile) {
    tile.cloud.classification.assign(tile.cloud.size(), 1);
    for (std::size_t i = 0; i < tile.cloud.size(); ++i)
        if (tile.cloud.positions[i].z() <= 0.001f && !tile.truth[i]) tile.cloud.classification[i] = 2;
}

// Airborne view of a conical crown: surface points on a grid of `spacing`, top at `height`
// above the ground, falling 2 m per metre of radius, plus a few stem points beneath.
inline void add_cone_crown(ToyTile& tile, float cx, float cy, float height, float radius, float spacing, float slope_deg, float roughness,
                           std::int32_t id) {
    const float ground = ground_height(cx, cy, slope_deg, roughness);
    for (float y = cy - radius; y <= cy + radius; y += spacing)
        for (float x = cx - radius; x <= cx + radius; x += spacing) {
            const float r = std::hypot(x - cx, y - cy);
            if (r <= radius) tile.add({x, y, ground + height - 2.0f * r}, id);
        }
    for (float z = 1.0f; z < height - 2.0f * radius; z += 1.0f) tile.add({cx + 0.1f, cy, ground + z}, id);
}

// Terrestrial view of a tree: a stem cylinder (5 degree, 2 cm steps) up into a solid ball crown
// sampled on a lattice of `lattice` metres.
inline void add_stem_and_ball(ToyTile& tile, float cx, float cy, float stem_radius, float crown_centre_height, float crown_radius,
                              float lattice, std::int32_t id) {
    for (float z = 0.0f; z <= crown_centre_height; z += 0.02f)
        for (int a = 0; a < 72; ++a) {
            const float t = static_cast<float>(a) * 5.0f * std::numbers::pi_v<float> / 180.0f;
            tile.add({cx + stem_radius * std::cos(t), cy + stem_radius * std::sin(t), z}, id);
        }
    for (float z = -crown_radius; z <= crown_radius; z += lattice)
        for (float y = -crown_radius; y <= crown_radius; y += lattice)
            for (float x = -crown_radius; x <= crown_radius; x += lattice)
                if (x * x + y * y + z * z <= crown_radius * crown_radius) tile.add({cx + x, cy + y, crown_centre_height + z}, id);
}

}  // namespace treelobes::test
