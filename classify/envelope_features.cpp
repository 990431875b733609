// Envelope features: the crown's outer shape and its coarse occupancy, meant to read the same
// whether the tree was scanned from the ground (TLS: dense stem and lower crown, the top
// occluded) or from the air (ALS: sparse, the top and outer crown surface seen best). Point
// counts per height depend on where the scanner stood; the crown outline (the outermost point
// per layer and azimuth sector) and whether a coarse cell holds any point at all depend much less.
#include "classify/feature_groups.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <numbers>

namespace treelobes::classify::detail {

namespace {

constexpr int kEnvelopeLayers = 10;   // envelope and occupancy layers (each H/10 high)
constexpr int kEnvelopeSectors = 16;  // azimuth sectors of the envelope
constexpr int kCellDivisor = 20;      // occupancy cells of size H/20
constexpr int kRings = 5;             // radial rings r / R in [0, 0.2), ..., [0.8, inf)

// Per layer: the area of the star-shaped polygon through the outermost point of each azimuth
// sector (an empty sector contributes radius 0), in m^2.
std::vector<double> layer_envelope_areas(const TreeFrame& f) {
    std::vector<std::vector<float>> outer(kEnvelopeLayers, std::vector<float>(kEnvelopeSectors, 0.0f));
    for (std::size_t i = 0; i < f.points.size(); ++i) {
        const int k = std::min(kEnvelopeLayers - 1, static_cast<int>(f.rel_height[i] * kEnvelopeLayers));
        const double phi = std::atan2(f.points[i].y(), f.points[i].x()) + std::numbers::pi;  // [0, 2 pi]
        const int s = std::min(kEnvelopeSectors - 1, static_cast<int>(phi / (2 * std::numbers::pi) * kEnvelopeSectors));
        outer[k][s] = std::max(outer[k][s], f.radius[i]);
    }
    const double wedge = 0.5 * std::sin(2 * std::numbers::pi / kEnvelopeSectors);
    std::vector<double> area(kEnvelopeLayers, 0.0);
    for (int k = 0; k < kEnvelopeLayers; ++k)
        for (int s = 0; s < kEnvelopeSectors; ++s) area[k] += wedge * outer[k][s] * outer[k][(s + 1) % kEnvelopeSectors];
    return area;
}

// Relative height below which `share` of the total of `per_layer` lies (linear within a layer).
double cumulative_height(const std::vector<double>& per_layer, double share) {
    double total = 0;
    for (double v : per_layer) total += v;
    if (total <= 0) return 0.0;
    double below = 0;
    const double target = share * total;
    for (std::size_t k = 0; k < per_layer.size(); ++k) {
        if (below + per_layer[k] >= target && per_layer[k] > 0)
            return (static_cast<double>(k) + (target - below) / per_layer[k]) / static_cast<double>(per_layer.size());
        below += per_layer[k];
    }
    return 1.0;
}

}  // namespace

void describe_envelope(Catalogue& c) {
    const std::string sectors = std::to_string(kEnvelopeSectors);
    for (int k = 0; k < kEnvelopeLayers; ++k)
        c.add(indexed("env_area", k), "1",
              "crown outline area in height layer " + std::to_string(k + 1) + " of 10 (h in [" + std::to_string(k) + ", " +
                      std::to_string(k + 1) + ") / 10): star polygon through the outermost voxel point of each of " + sectors +
                      " azimuth sectors, / (pi R^2)");
    for (int k = 0; k < kEnvelopeLayers; ++k)
        c.add(indexed("env_volume_share", k), "1",
              "share of the envelope volume (sum of the layer outline areas) in height layer " + std::to_string(k + 1) + " of 10");
    for (int d = 1; d <= 9; ++d)
        c.add(indexed("env_volume_decile", d), "1",
              "relative height h below which " + std::to_string(10 * d) + " % of the envelope volume lies (linear within layers)");
    c.add("env_volume_ratio", "1", "envelope volume (layer outline areas x H/10) / (pi R^2 H)");
    c.add("env_widest_layer", "1", "relative height of the centre of the layer with the largest outline area");
    for (int k = 0; k < kEnvelopeLayers; ++k)
        c.add(indexed("occ_share", k), "1",
              "share of the occupied cells (size H/20, any point counts once) in height layer " + std::to_string(k + 1) + " of 10");
    for (int d = 1; d <= 9; ++d)
        c.add(indexed("occ_decile", d), "1",
              std::to_string(10 * d) + " % quantile of the occupied cells' centre heights / H (cells of size H/20)");
    for (int k = 0; k < kRings; ++k) {
        const std::string ring = "ring " + std::to_string(k + 1) + " of " + std::to_string(kRings) + " (r / R in [" +
                                 std::to_string(2 * k) + ", " + std::to_string(2 * k + 2) + ") / 10" + (k + 1 == kRings ? ", open" : "") +
                                 ")";
        c.add(indexed("ring_top", k), "1",
              "95 % quantile of h of the voxel points in " + ring + " (the crown's upper surface seen from above)");
        c.add(indexed("ring_bottom", k), "1",
              "5 % quantile of h of the voxel points in " + ring + " above 0.05 H (how low the crown hangs: weeping branches)");
        c.add(indexed("ring_depth", k), "1", "ring_top - ring_bottom of " + ring);
    }
    c.add("occ_plan_ratio", "1", "occupied ground-plan cells (size H/20) x cell area / (pi R^2)");
    c.add("occ_fill_ratio", "1", "occupied cells (size H/20) x cell volume / envelope volume (how much of the envelope is filled)");
}

void compute_envelope(const TreeFrame& f, FeatureSink& out) {
    const std::vector<double> area = layer_envelope_areas(f);
    const double disc = std::numbers::pi * f.crown_radius * f.crown_radius;
    double volume = 0;
    for (double a : area) volume += a * f.height / kEnvelopeLayers;
    for (int k = 0; k < kEnvelopeLayers; ++k) out.add(indexed("env_area", k), area[k] / disc);
    for (int k = 0; k < kEnvelopeLayers; ++k)
        out.add(indexed("env_volume_share", k), volume > 0 ? area[k] * f.height / kEnvelopeLayers / volume : 0.0);
    for (int d = 1; d <= 9; ++d) out.add(indexed("env_volume_decile", d), cumulative_height(area, d / 10.0));
    out.add("env_volume_ratio", volume / (disc * f.height));
    const auto widest = std::max_element(area.begin(), area.end()) - area.begin();
    out.add("env_widest_layer", (static_cast<double>(widest) + 0.5) / kEnvelopeLayers);

    // Cells indexed in the tree frame (origin on the stem axis at the ground), so they turn and
    // move with the tree.
    const float cell = f.height / kCellDivisor;
    std::set<std::tuple<long, long, long>> cells;
    std::set<std::pair<long, long>> plan;
    for (const auto& p : f.points) {
        const long x = std::lround(std::floor(p.x() / cell)), y = std::lround(std::floor(p.y() / cell));
        const long z = std::clamp(std::lround(std::floor(p.z() / cell)), 0L, static_cast<long>(kCellDivisor - 1));
        cells.insert({x, y, z});
        plan.insert({x, y});
    }
    std::vector<double> per_layer(kEnvelopeLayers, 0.0);
    std::vector<float> heights;
    for (const auto& [x, y, z] : cells) {
        per_layer[std::min<long>(kEnvelopeLayers - 1, z * kEnvelopeLayers / kCellDivisor)] += 1.0;
        heights.push_back((static_cast<float>(z) + 0.5f) / kCellDivisor);
    }
    const double occupied = static_cast<double>(cells.size());
    for (int k = 0; k < kEnvelopeLayers; ++k) out.add(indexed("occ_share", k), occupied > 0 ? per_layer[k] / occupied : 0.0);
    for (int d = 1; d <= 9; ++d) out.add(indexed("occ_decile", d), quantile(heights, d / 10.0));
    // Top and bottom surfaces per ring. The lowest 5 % of the height (stem foot, ground) is left
    // out of the bottom, so a visible trunk does not make every inner ring reach the ground.
    std::vector<std::vector<float>> ring_h(kRings), ring_low(kRings);
    for (std::size_t i = 0; i < f.points.size(); ++i) {
        const int k = std::min(kRings - 1, static_cast<int>(f.radius[i] / f.crown_radius * kRings));
        ring_h[k].push_back(f.rel_height[i]);
        if (f.rel_height[i] > 0.05f) ring_low[k].push_back(f.rel_height[i]);
    }
    for (int k = 0; k < kRings; ++k) {
        const float top = quantile(ring_h[k], 0.95), bottom = quantile(ring_low[k], 0.05);
        out.add(indexed("ring_top", k), top);
        out.add(indexed("ring_bottom", k), bottom);
        out.add(indexed("ring_depth", k), ring_low[k].empty() ? 0.0f : top - bottom);
    }
    out.add("occ_plan_ratio", static_cast<double>(plan.size()) * cell * cell / disc);
    out.add("occ_fill_ratio", volume > 0 ? occupied * cell * cell * cell / volume : 0.0);
}

}  // namespace treelobes::classify::detail
