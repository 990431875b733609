#include "segment/segment_trees.hpp"

#include "core/asprs_classes.hpp"
#include "core/error.hpp"
#include "geometry/euclidean_clusters.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/neighbour_graph.hpp"
#include "geometry/ransac_fit.hpp"
#include "geometry/shortest_paths.hpp"
#include "geometry/union_find.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <limits>
#include <optional>
#include <queue>
#include <span>
#include <tuple>
#include <unordered_map>
#include <unordered_set>

namespace treelobes {

namespace {

void check_options(const SegmentOptions& o) {
    const auto positive = [](float v, const char* name) {
        if (!(v > 0.0f) || !std::isfinite(v)) throw Error::usage(std::string("segment: ") + name + " must be > 0");
    };
    const auto share = [](float v, const char* name) {
        if (!(v >= 0.0f && v <= 1.0f)) throw Error::usage(std::string("segment: ") + name + " must be in 0..1");
    };
    if (!(o.min_tree_height >= 0.0f) || !std::isfinite(o.min_tree_height)) throw Error::usage("segment: min tree height must be >= 0");
    positive(o.terrestrial_density, "terrestrial density");
    positive(o.chm_cell, "CHM cell");
    if (!(o.point_radius >= 0.0f) || !std::isfinite(o.point_radius)) throw Error::usage("segment: point radius must be >= 0");
    // A cell or disc of several spacings would blur neighbouring crowns into one.
    if (!(o.cell_per_spacing >= 0.0f && o.cell_per_spacing <= 4.0f)) throw Error::usage("segment: cell per spacing must be in 0..4");
    if (!(o.disc_per_spacing >= 0.0f && o.disc_per_spacing <= 4.0f)) throw Error::usage("segment: disc per spacing must be in 0..4");
    // Returns 10 m apart (0.01 per m^2) no longer show a crown.
    if (!(o.return_spacing >= 0.0f && o.return_spacing <= 10.0f)) throw Error::usage("segment: return spacing must be in 0..10 metres");
    positive(o.pit_depth, "pit depth");
    if (!(o.chm_smoothing >= 0.0f) || !std::isfinite(o.chm_smoothing)) throw Error::usage("segment: CHM smoothing must be >= 0");
    positive(o.window_base, "window base");
    if (!(o.window_per_metre >= 0.0f) || !std::isfinite(o.window_per_metre)) throw Error::usage("segment: window per metre must be >= 0");
    positive(o.max_window, "max window");
    if (!(o.min_top_prominence >= 0.0f) || !std::isfinite(o.min_top_prominence))
        throw Error::usage("segment: min top prominence must be >= 0");
    share(o.top_prominence_ratio, "top prominence ratio");
    share(o.merge_pass_ratio, "merge pass ratio");
    share(o.seed_ratio, "seed ratio");
    share(o.crown_ratio, "crown ratio");
    positive(o.max_crown_radius, "max crown radius");
    if (!(o.stem_slice_high > o.stem_slice_low) || !std::isfinite(o.stem_slice_low) || !std::isfinite(o.stem_slice_high))
        throw Error::usage("segment: the stem slice needs low < high");
    positive(o.stem_cluster_distance, "stem cluster distance");
    if (!(o.stem_subcluster_distance >= 0.0f && o.stem_subcluster_distance < o.stem_cluster_distance))
        throw Error::usage("segment: stem subcluster distance must be >= 0 and below the stem cluster distance");
    if (!(o.stem_merge_distance >= 0.0f) || !std::isfinite(o.stem_merge_distance))
        throw Error::usage("segment: stem merge distance must be >= 0");
    if (!(o.shared_top_stem_distance >= 0.0f) || !std::isfinite(o.shared_top_stem_distance))
        throw Error::usage("segment: shared top stem distance must be >= 0");
    if (!(o.shared_top_distance >= 0.0f) || !std::isfinite(o.shared_top_distance))
        throw Error::usage("segment: shared top distance must be >= 0");
    if (o.min_stem_points < 5) throw Error::usage("segment: min stem points must be >= 5");
    positive(o.min_stem_radius, "min stem radius");
    if (!(o.max_stem_radius > o.min_stem_radius)) throw Error::usage("segment: max stem radius must exceed min stem radius");
    positive(o.circle_tolerance, "circle tolerance");
    share(o.min_circle_inliers, "min circle inliers");
    share(o.min_arc_coverage, "min arc coverage");
    if (!(o.max_stem_lean >= 0.0f && o.max_stem_lean < 90.0f)) throw Error::usage("segment: max stem lean must be in 0..90 degrees");
    if (!(o.min_quarter_arc_share >= 0.0f && o.min_quarter_arc_share <= 1.0f))
        throw Error::usage("segment: min quarter arc share must be in 0..1");
    // Thinner layers than a few centimetres hold too few points for a circle, and a layer count
    // of slice height / layer height must stay small.
    if (!(o.stem_layer_height >= 0.05f && o.stem_layer_height <= 10.0f))
        throw Error::usage("segment: stem layer height must be in 0.05..10 metres");
    if (!(o.trunk_layer_height >= 0.05f && o.trunk_layer_height <= 10.0f))
        throw Error::usage("segment: trunk layer height must be in 0.05..10 metres");
    positive(o.graph_voxel, "graph voxel");
    if (o.graph_neighbours < 2 || o.graph_neighbours > 64) throw Error::usage("segment: graph neighbours must be in 2..64");
    positive(o.max_gap, "max gap");
    if (!(o.attach_gap >= 0.0f) || !std::isfinite(o.attach_gap)) throw Error::usage("segment: attach gap must be >= 0");
    if (!(o.detached_min_height >= 0.0f) || !std::isfinite(o.detached_min_height))
        throw Error::usage("segment: detached min height must be >= 0");
    if (o.min_detached_voxels < 1) throw Error::usage("segment: min detached voxels must be >= 1");
    positive(o.graph_beta, "graph beta");
    if (!(o.stem_reach_exponent >= 0.0f && o.stem_reach_exponent <= 4.0f))
        throw Error::usage("segment: stem reach exponent must be in 0..4");
    if (!(o.ground_clearance >= 0.0f) || !std::isfinite(o.ground_clearance)) throw Error::usage("segment: ground clearance must be >= 0");
}

void check_terrain_of(const PointCloud& cloud, const Terrain& terrain) {
    if (terrain.height_above_ground.size() != cloud.size() || terrain.is_ground.size() != cloud.size())
        throw Error(ExitCode::Internal, "segment: the terrain was computed for another cloud (" +
                                                std::to_string(terrain.height_above_ground.size()) + " heights for " +
                                                std::to_string(cloud.size()) + " points)");
}

std::string format(const char* pattern, double a, double b = 0, double c = 0) {
    char text[256];
    std::snprintf(text, sizeof text, pattern, a, b, c);
    return text;
}

// Points that may belong to a tree: not ground, not of a class that is never a tree's (noise,
// buildings, water, wires, ...: core/asprs_classes.hpp), at least `clearance` above the DTM.
std::vector<std::uint8_t> vegetation_points(const PointCloud& cloud, const Terrain& terrain, float clearance) {
    std::vector<std::uint8_t> keep(cloud.size(), 0);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const bool not_a_tree = !cloud.classification.empty() && asprs_never_a_tree(cloud.classification[i]);
        keep[i] = !not_a_tree && !terrain.is_ground[i] && terrain.height_above_ground[i] >= clearance;
    }
    return keep;
}

// The vegetation points and the square cells of edge `cell` (metres) that hold any of them.
struct OccupiedCells {
    std::size_t points = 0;
    std::size_t cells = 0;
    // Points per square metre over the occupied cells (0 without vegetation).
    double density(double cell) const { return cells ? static_cast<double>(points) / (static_cast<double>(cells) * cell * cell) : 0.0; }
};

OccupiedCells occupied_cells(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation, float cell) {
    std::unordered_set<std::int64_t> cells;
    OccupiedCells occupied;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!vegetation[i]) continue;
        const auto x = static_cast<std::int64_t>(std::floor(cloud.positions[i].x() / cell));
        const auto y = static_cast<std::int64_t>(std::floor(cloud.positions[i].y() / cell));
        cells.insert(x * 2000003 + y);
        ++occupied.points;
    }
    occupied.cells = cells.size();
    return occupied;
}

// Airborne or terrestrial from the density of the vegetation points over the occupied 1 m cells:
// an airborne survey gives 1-100 points per square metre, a terrestrial scan hundreds to thousands.
ScanMode choose_mode(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation, const SegmentOptions& options,
                     std::string& reason) {
    const OccupiedCells occupied = occupied_cells(cloud, vegetation, 1.0f);
    const double density = occupied.density(1.0);
    const bool terrestrial = density >= options.terrestrial_density;
    reason = format("automatic: %.0f vegetation points per m^2 over %.0f occupied m^2 ", density, static_cast<double>(occupied.cells)) +
             (terrestrial ? ">= " : "< ") + format("%.0f", options.terrestrial_density) +
             (terrestrial ? " (dense: terrestrial)" : " (sparse: airborne)");
    return terrestrial ? ScanMode::Terrestrial : ScanMode::Airborne;
}

// ---------------------------------------------------------------------------------------------
// Airborne: canopy height model, treetops, crowns.

struct Raster {
    double x0 = 0, y0 = 0;  // local xy of the corner of cell (0, 0)
    float cell = 1;
    int columns = 0, rows = 0;
    std::vector<float> values;
    std::size_t index(int c, int r) const { return static_cast<std::size_t>(r) * columns + c; }
    int column_of(float x) const { return std::clamp(static_cast<int>(std::floor((x - x0) / cell)), 0, columns - 1); }
    int row_of(float y) const { return std::clamp(static_cast<int>(std::floor((y - y0) / cell)), 0, rows - 1); }
    Eigen::Vector2f centre(int c, int r) const {
        return {static_cast<float>(x0 + (c + 0.5) * cell), static_cast<float>(y0 + (r + 0.5) * cell)};
    }
};

// Highest height above ground per cell, each point drawn as a disc (lidR's p2r subcircle), so
// that the gaps between sparse returns do not open pits in the crowns.
Raster highest_points_raster(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                             const SegmentOptions& options) {
    const auto [low, high] = cloud.bounds();
    Raster chm;
    chm.cell = options.chm_cell;
    chm.x0 = std::floor(low.x() / chm.cell) * chm.cell;
    chm.y0 = std::floor(low.y() / chm.cell) * chm.cell;
    chm.columns = static_cast<int>(std::floor((high.x() - chm.x0) / chm.cell)) + 1;
    chm.rows = static_cast<int>(std::floor((high.y() - chm.y0) / chm.cell)) + 1;
    chm.values.assign(static_cast<std::size_t>(chm.columns) * chm.rows, std::numeric_limits<float>::quiet_NaN());
    const float r = options.point_radius;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!vegetation[i]) continue;
        const Eigen::Vector3f& p = cloud.positions[i];
        const float h = terrain.height_above_ground[i];
        for (int row = chm.row_of(p.y() - r); row <= chm.row_of(p.y() + r); ++row)
            for (int col = chm.column_of(p.x() - r); col <= chm.column_of(p.x() + r); ++col) {
                const bool own = col == chm.column_of(p.x()) && row == chm.row_of(p.y());
                if (!own && (chm.centre(col, row) - p.head<2>()).squaredNorm() > r * r) continue;
                float& v = chm.values[chm.index(col, row)];
                if (!(v >= h)) v = h;
            }
    }
    return chm;
}

// Cells without returns or far below the median of their neighbours are pits (Ben-Arie et al.
// 2009, §2): they take that median. Cells no neighbour covers are open ground (0).
void fill_pits(Raster& chm, float depth) {
    std::vector<float> out = chm.values;
    std::vector<float> around;
    for (int r = 0; r < chm.rows; ++r)
        for (int c = 0; c < chm.columns; ++c) {
            around.clear();
            for (int dr = -1; dr <= 1; ++dr)
                for (int dc = -1; dc <= 1; ++dc) {
                    const int rr = r + dr, cc = c + dc;
                    if ((dr == 0 && dc == 0) || rr < 0 || cc < 0 || rr >= chm.rows || cc >= chm.columns) continue;
                    const float v = chm.values[chm.index(cc, rr)];
                    if (std::isfinite(v)) around.push_back(v);
                }
            float& v = out[chm.index(c, r)];
            if (around.size() < 5) {
                if (!std::isfinite(v)) v = 0.0f;
                continue;
            }
            std::nth_element(around.begin(), around.begin() + around.size() / 2, around.end());
            const float median = around[around.size() / 2];
            if (!std::isfinite(v) || v < median - depth) v = median;
        }
    chm.values.swap(out);
}

// Cells the smoothing kernel reaches on either side (3 sigma; none without smoothing).
int smoothing_reach(const Raster& chm, float sigma) {
    return sigma > 0.0f ? std::max(1, static_cast<int>(std::ceil(3.0f * sigma / chm.cell))) : 0;
}

// Gaussian smoothing (separable, kernel to 3 sigma) of the CHM the tops are searched on: the
// leaf clumps of a broad crown make many small maxima that smoothing removes while the peaks of
// separate crowns stay (Popescu & Wynne 2004, §2.3 smooth their CHM the same way).
Raster smoothed(const Raster& chm, float sigma) {
    if (sigma <= 0.0f) return chm;
    const float s = sigma / chm.cell;
    const int reach = smoothing_reach(chm, sigma);
    std::vector<float> kernel(static_cast<std::size_t>(2 * reach + 1));
    for (int k = -reach; k <= reach; ++k) kernel[static_cast<std::size_t>(k + reach)] = std::exp(-0.5f * k * k / (s * s));
    const auto pass = [&](const std::vector<float>& in, bool along_rows) {
        std::vector<float> out(in.size());
        for (int r = 0; r < chm.rows; ++r)
            for (int c = 0; c < chm.columns; ++c) {
                double sum = 0, weights = 0;
                for (int k = -reach; k <= reach; ++k) {
                    const int cc = along_rows ? c + k : c, rr = along_rows ? r : r + k;
                    if (cc < 0 || rr < 0 || cc >= chm.columns || rr >= chm.rows) continue;
                    const double w = kernel[static_cast<std::size_t>(k + reach)];
                    sum += w * in[chm.index(cc, rr)];
                    weights += w;
                }
                out[chm.index(c, r)] = static_cast<float>(sum / weights);
            }
        return out;
    };
    Raster out = chm;
    out.values = pass(pass(chm.values, true), false);
    return out;
}

// Cells higher than every other cell within a window whose diameter grows with their height
// (Popescu & Wynne 2004, §2.4). Of equal heights the first cell in row-major order wins.
std::vector<std::size_t> find_treetops(const Raster& chm, const SegmentOptions& options) {
    std::vector<std::size_t> tops;
    for (int r = 0; r < chm.rows; ++r)
        for (int c = 0; c < chm.columns; ++c) {
            const std::size_t here = chm.index(c, r);
            const float h = chm.values[here];
            if (!(h >= options.min_tree_height)) continue;
            const float diameter = std::min(options.max_window, options.window_base + options.window_per_metre * h);
            const int reach = static_cast<int>(std::floor(0.5f * diameter / chm.cell));
            const float reach_squared = (0.5f * diameter / chm.cell) * (0.5f * diameter / chm.cell);
            bool highest = true;
            for (int dr = -reach; dr <= reach && highest; ++dr)
                for (int dc = -reach; dc <= reach; ++dc) {
                    const int rr = r + dr, cc = c + dc;
                    if ((dr == 0 && dc == 0) || rr < 0 || cc < 0 || rr >= chm.rows || cc >= chm.columns) continue;
                    if (static_cast<float>(dr * dr + dc * dc) > reach_squared) continue;
                    const std::size_t there = chm.index(cc, rr);
                    const float v = chm.values[there];
                    if (v > h || (v == h && there < here)) {
                        highest = false;
                        break;
                    }
                }
            if (highest) tops.push_back(here);
        }
    // Highest first: ids follow the height order, and crowns grow from the highest tops first.
    std::stable_sort(tops.begin(), tops.end(), [&](std::size_t a, std::size_t b) { return chm.values[a] > chm.values[b]; });
    return tops;
}

// Regions flooded from the tops over the CHM, highest candidate cell first (a watershed from
// markers, Li et al. 2012, §2.2 ordering): a neighbouring cell joins the region that reaches it
// first when `admit(cell, region)` allows. Returns the region index + 1 per cell (0 = none).
template <typename Admit>
std::vector<std::int32_t> flood_from_tops(const Raster& chm, const std::vector<std::size_t>& tops, Admit admit) {
    std::vector<std::int32_t> region(chm.values.size(), 0);
    struct Candidate {
        float height;
        std::size_t cell;
        std::int32_t region;
        bool operator<(const Candidate& o) const {  // max-heap: highest, then lowest cell, then lowest region
            if (height != o.height) return height < o.height;
            if (cell != o.cell) return cell > o.cell;
            return region > o.region;
        }
    };
    std::priority_queue<Candidate> front;
    for (std::size_t t = 0; t < tops.size(); ++t) front.push({chm.values[tops[t]], tops[t], static_cast<std::int32_t>(t + 1)});
    while (!front.empty()) {
        const Candidate next = front.top();
        front.pop();
        if (region[next.cell]) continue;
        const auto t = static_cast<std::size_t>(next.region - 1);
        if (next.cell != tops[t] && !admit(next.cell, t)) continue;
        region[next.cell] = next.region;
        const int c = static_cast<int>(next.cell % chm.columns), r = static_cast<int>(next.cell / chm.columns);
        for (int dr = -1; dr <= 1; ++dr)
            for (int dc = -1; dc <= 1; ++dc) {
                const int rr = r + dr, cc = c + dc;
                if ((dr == 0 && dc == 0) || rr < 0 || cc < 0 || rr >= chm.rows || cc >= chm.columns) continue;
                const std::size_t there = chm.index(cc, rr);
                if (!region[there]) front.push({chm.values[there], there, next.region});
            }
    }
    return region;
}

float cell_distance(const Raster& chm, std::size_t a, std::size_t b) {
    const int ac = static_cast<int>(a % chm.columns), ar = static_cast<int>(a / chm.columns);
    const int bc = static_cast<int>(b % chm.columns), br = static_cast<int>(b / chm.columns);
    return chm.cell * std::hypot(static_cast<float>(ac - bc), static_cast<float>(ar - br));
}

// Keeps the tops that stand out. Branch clusters of one broad crown make local maxima separated
// by shallow saddles from a nearby higher top. The watershed basins of all tops are merged
// across their highest passes, highest pass first (union-find, as in computing dynamics,
// Grimaud 1992, §3): the group with the lower peak joins when its peak rises less than
// max(min_top_prominence, top_prominence_ratio x its height) above the pass and the pass is
// high in the other group's crown (at least merge_pass_ratio x its peak: a small tree touching
// a tall neighbour's lower crown is still a tree). The peaks of the merged groups are the tops
// that remain.
std::vector<std::size_t> prominent_tops(const Raster& chm, const std::vector<std::size_t>& tops, const SegmentOptions& options) {
    const std::vector<std::int32_t> basin =
            flood_from_tops(chm, tops, [&](std::size_t cell, std::size_t) { return chm.values[cell] >= options.min_tree_height; });
    // Highest pass between every pair of touching basins.
    std::map<std::pair<std::int32_t, std::int32_t>, float> passes;
    for (int r = 0; r < chm.rows; ++r)
        for (int c = 0; c < chm.columns; ++c) {
            const std::size_t here = chm.index(c, r);
            if (!basin[here]) continue;
            for (const auto& [dc, dr] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}, std::pair{-1, 1}}) {
                const int cc = c + dc, rr = r + dr;
                if (cc < 0 || cc >= chm.columns || rr >= chm.rows) continue;
                const std::size_t there = chm.index(cc, rr);
                if (!basin[there] || basin[there] == basin[here]) continue;
                const auto key = std::minmax(basin[here], basin[there]);
                const float pass = std::min(chm.values[here], chm.values[there]);
                auto [it, added] = passes.emplace(key, pass);
                if (!added) it->second = std::max(it->second, pass);
            }
        }
    std::vector<std::tuple<float, std::int32_t, std::int32_t>> order;
    for (const auto& [key, pass] : passes) order.emplace_back(pass, key.first, key.second);
    std::sort(order.begin(), order.end(),
              [](const auto& a, const auto& b) { return std::get<0>(a) != std::get<0>(b) ? std::get<0>(a) > std::get<0>(b) : a < b; });
    UnionFind groups(tops.size());
    std::vector<std::size_t> peak(tops.size());  // per group root: index into tops of its highest top
    for (std::size_t t = 0; t < tops.size(); ++t) peak[t] = t;
    for (const auto& [pass, a, b] : order) {
        const int ra = groups.find(a - 1), rb = groups.find(b - 1);
        if (ra == rb) continue;
        const std::size_t pa = peak[static_cast<std::size_t>(ra)], pb = peak[static_cast<std::size_t>(rb)];
        // tops are sorted highest first, so the smaller index is the higher peak.
        const std::size_t high = std::min(pa, pb), low = std::max(pa, pb);
        const float rise = chm.values[tops[low]] - pass;
        const bool shallow = rise < std::max(options.min_top_prominence, options.top_prominence_ratio * chm.values[tops[low]]);
        if (!shallow || pass < options.merge_pass_ratio * chm.values[tops[high]]) continue;
        groups.unite(ra, rb);
        peak[static_cast<std::size_t>(groups.find(ra))] = high;
    }
    std::vector<std::size_t> kept;
    for (std::size_t t = 0; t < tops.size(); ++t)
        if (groups.find(static_cast<int>(t)) == static_cast<int>(t)) kept.push_back(tops[peak[t]]);
    std::stable_sort(kept.begin(), kept.end(), [&](std::size_t a, std::size_t b) { return chm.values[a] > chm.values[b]; });
    return kept;
}

// The highest cell within `reach` cells of `cell` (a square window).
float highest_near(const Raster& chm, std::size_t cell, int reach) {
    const int c = static_cast<int>(cell % chm.columns), r = static_cast<int>(cell / chm.columns);
    float highest = chm.values[cell];
    for (int rr = std::max(0, r - reach); rr <= std::min(chm.rows - 1, r + reach); ++rr)
        for (int cc = std::max(0, c - reach); cc <= std::min(chm.columns - 1, c + reach); ++cc)
            highest = std::max(highest, chm.values[chm.index(cc, rr)]);
    return highest;
}

// Crowns grown from the tops over the CHM (Dalponte & Coomes 2016, §2.3 admission rules): a cell
// joins the neighbouring crown that reaches it when it is above min_tree_height, above
// seed_ratio x the crown's top, above crown_ratio x the crown's mean height, not higher than the
// top, and within max_crown_radius of it. Returns the crown index + 1 per cell (0 = none).
// The tops were found on the smoothed CHM, whose maximum can lie a cell or two beside the raw
// one: a crown's top height is the highest raw cell the smoothing mixed into its top cell.
// Taken at the top cell itself, the raw cells beside it that are higher were refused, and a
// crown could end as that one cell (an oak of 12.6 m in the ALS bench kept 1 point of 1,185).
std::vector<std::int32_t> grow_crowns(const Raster& chm, const std::vector<std::size_t>& tops, const SegmentOptions& options) {
    std::vector<double> sum(tops.size(), 0.0);
    std::vector<std::uint32_t> count(tops.size(), 0);
    std::vector<float> top_height(tops.size());
    for (std::size_t t = 0; t < tops.size(); ++t) {
        top_height[t] = highest_near(chm, tops[t], smoothing_reach(chm, options.chm_smoothing));
        sum[t] = chm.values[tops[t]];
        count[t] = 1;
    }
    return flood_from_tops(chm, tops, [&](std::size_t cell, std::size_t t) {
        const float h = chm.values[cell], top = top_height[t];
        if (h < options.min_tree_height || h < options.seed_ratio * top || h < options.crown_ratio * sum[t] / count[t] || h > top ||
            cell_distance(chm, cell, tops[t]) > options.max_crown_radius)
            return false;
        sum[t] += h;
        ++count[t];
        return true;
    });
}

// Per-point labels -> trees: drops labels without points or lower than min_tree_height,
// renumbers the rest 1.. in label order, and measures top, base and point count.
std::vector<SegmentedTree> collect_trees(const PointCloud& cloud, const Terrain& terrain, std::vector<std::int32_t>& tree_id,
                                         std::size_t labels, const std::vector<Eigen::Vector2f>& stem_xy,
                                         const std::vector<float>& stem_radius, float min_tree_height) {
    std::vector<std::size_t> count(labels + 1, 0);
    std::vector<int> highest(labels + 1, -1);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto label = static_cast<std::size_t>(tree_id[i]);
        if (!label) continue;
        ++count[label];
        if (highest[label] < 0 || terrain.height_above_ground[i] > terrain.height_above_ground[static_cast<std::size_t>(highest[label])])
            highest[label] = static_cast<int>(i);
    }
    std::vector<std::int32_t> renumber(labels + 1, 0);
    std::vector<SegmentedTree> trees;
    for (std::size_t label = 1; label <= labels; ++label) {
        if (!count[label] || terrain.height_above_ground[static_cast<std::size_t>(highest[label])] < min_tree_height) continue;
        SegmentedTree tree;
        tree.id = static_cast<std::int32_t>(trees.size() + 1);
        tree.top = cloud.positions[static_cast<std::size_t>(highest[label])];
        const Eigen::Vector2f xy = stem_xy.empty() ? Eigen::Vector2f(tree.top.head<2>()) : stem_xy[label - 1];
        tree.base = Eigen::Vector3f(xy.x(), xy.y(), terrain.dtm.height_at(xy.x(), xy.y()));
        tree.points = count[label];
        tree.stem_radius = stem_radius.empty() ? 0.0f : stem_radius[label - 1];
        renumber[label] = tree.id;
        trees.push_back(tree);
    }
    for (auto& id : tree_id) id = renumber[static_cast<std::size_t>(id)];
    return trees;
}

// Mean spacing of the vegetation returns seen from above (segment_trees.hpp).
float return_spacing_of(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation) {
    const double density = occupied_cells(cloud, vegetation, 2.0f).density(2.0);
    return density > 0.0 ? static_cast<float>(1.0 / std::sqrt(density)) : 0.0f;
}

// The CHM's cell and discs grow with the returns' spacing (and the cell as for the DTM where the
// points are too few for the tile's extent). At 1-2 pulses per m^2 (many national surveys) 0.15 m
// discs on 0.5 m cells leave most cells empty, every return stands alone as a local maximum, and
// synthetic tiles with 25 trees gave 100-380 "trees" each (docs/segment.md).
SegmentOptions with_chm_grid_for_spacing(const PointCloud& cloud, SegmentOptions options, float spacing) {
    options.chm_cell = grid_cell_for_points(cloud, std::max(options.chm_cell, options.cell_per_spacing * spacing));
    options.point_radius = std::max(options.point_radius, options.disc_per_spacing * spacing);
    return options;
}

void segment_airborne(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                      const SegmentOptions& requested, TreeSegmentation& result) {
    result.return_spacing = requested.return_spacing > 0.0f ? requested.return_spacing : return_spacing_of(cloud, vegetation);
    const SegmentOptions options = with_chm_grid_for_spacing(cloud, requested, result.return_spacing);
    result.chm_cell = options.chm_cell;
    result.chm_point_radius = options.point_radius;
    Raster chm = highest_points_raster(cloud, terrain, vegetation, options);
    fill_pits(chm, options.pit_depth);
    const Raster smooth = smoothed(chm, options.chm_smoothing);
    const std::vector<std::size_t> tops = prominent_tops(smooth, find_treetops(smooth, options), options);
    const std::vector<std::int32_t> crown = grow_crowns(chm, tops, options);
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (vegetation[i]) result.tree_id[i] = crown[chm.index(chm.column_of(cloud.positions[i].x()), chm.row_of(cloud.positions[i].y()))];
    result.trees = collect_trees(cloud, terrain, result.tree_id, tops.size(), {}, {}, options.min_tree_height);
}

// ---------------------------------------------------------------------------------------------
// Terrestrial: stems in a slice, then one multi-source Dijkstra over the plot.

struct Stem {
    Eigen::Vector2f centre;
    float radius = 0;
    std::size_t inliers = 0;
    std::vector<int> points;  // indices into the cloud: the stem's slice points
};

// Euclidean clusters of the slice points (single linkage at `distance`), each as cloud indices.
std::vector<std::vector<int>> cluster_slice(const PointCloud& cloud, const std::vector<int>& slice, float distance) {
    std::vector<Eigen::Vector3f> points;
    points.reserve(slice.size());
    for (int i : slice) points.push_back(cloud.positions[static_cast<std::size_t>(i)]);
    std::vector<std::vector<int>> clusters = euclidean_clusters(points, distance);
    for (auto& cluster : clusters)
        for (int& member : cluster) member = slice[static_cast<std::size_t>(member)];
    return clusters;
}

// A stem stands upright: the centroids of the lower and upper halves of its samples (its slice
// points on the circle, or the centres of its layers' circles) lie above each other within
// `max_lean_degrees`. A low branch crossing the slice aslant can fit a circle arc too, but its
// halves are offset by its horizontal run.
bool upright(std::span<const Eigen::Vector3f> samples, float max_lean_degrees) {
    float low = std::numeric_limits<float>::infinity(), high = -low;
    for (const Eigen::Vector3f& p : samples) {
        low = std::min(low, p.z());
        high = std::max(high, p.z());
    }
    const float middle = 0.5f * (low + high);
    Eigen::Vector3d sum[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    std::size_t count[2] = {0, 0};
    for (const Eigen::Vector3f& p : samples) {
        const int half = p.z() >= middle;
        sum[half] += p.cast<double>();
        ++count[half];
    }
    if (!count[0] || !count[1]) return false;
    const Eigen::Vector3d step = sum[1] / count[1] - sum[0] / count[0];
    const double tangent = std::tan(static_cast<double>(max_lean_degrees) * std::numbers::pi / 180.0);
    return step.z() > 0 && step.head<2>().norm() <= tangent * step.z();
}

// A trunk holds its arc through the slice's whole height. A limb that droops across the slice
// does not: its band of points fits a wide arc that only some heights fill. Such a limb of a fig
// passed for a 0.77 m stem on a crowded plot and took 13 % of its tree points (docs/segment.md).
// The lowest quarter is not judged, since a root flare widens there. `samples` are the circle's
// points as (x, y, height above the DTM).
bool arc_in_every_upper_quarter(std::span<const Eigen::Vector3f> samples, const Eigen::Vector2f& centre, const SegmentOptions& options) {
    if (options.min_quarter_arc_share <= 0.0f) return true;
    constexpr int kSectors = 36;
    std::uint64_t all = 0, quarter[4] = {0, 0, 0, 0};
    const float span = options.stem_slice_high - options.stem_slice_low;
    for (const Eigen::Vector3f& p : samples) {
        const Eigen::Vector2f d = p.head<2>() - centre;
        const float turn = (std::atan2(d.y(), d.x()) + std::numbers::pi_v<float>) / (2.0f * std::numbers::pi_v<float>);
        const int sector = std::clamp(static_cast<int>(turn * kSectors), 0, kSectors - 1);
        const int q = std::clamp(static_cast<int>((p.z() - options.stem_slice_low) / span * 4.0f), 0, 3);
        all |= std::uint64_t{1} << sector;
        quarter[q] |= std::uint64_t{1} << sector;
    }
    const float needed = options.min_quarter_arc_share * static_cast<float>(std::popcount(all));
    for (int q = 1; q < 4; ++q)
        if (static_cast<float>(std::popcount(quarter[q])) < needed) return false;
    return true;
}

// The points as (x, y, height above the DTM). The slice is cut by height above the DTM, so on a
// slope its uphill side lies higher than its downhill side: split by z, the halves of a thick
// trunk would be its downhill and uphill arcs, offset by its diameter however upright it stands.
std::vector<Eigen::Vector3f> above_ground(const PointCloud& cloud, const std::vector<float>& height_above_ground,
                                          const std::vector<int>& points) {
    std::vector<Eigen::Vector3f> samples;
    samples.reserve(points.size());
    for (int i : points) {
        const auto k = static_cast<std::size_t>(i);
        samples.emplace_back(cloud.positions[k].x(), cloud.positions[k].y(), height_above_ground[k]);
    }
    return samples;
}

// Does a circle of a plausible radius hold enough of these points around enough of its
// circumference (Liang et al. 2012, §2.2)?
bool circle_holds(const CircleFit& circle, std::size_t points, const SegmentOptions& options) {
    return circle.ok && static_cast<float>(circle.inliers) >= options.min_circle_inliers * static_cast<float>(points) &&
           circle.coverage >= options.min_arc_coverage;
}

// A trunk that tapers within the slice (a root flare: the synthetic oaks, figs and mahoganies of
// 1.0-1.5 m narrow by a third between 1 and 2 m above the ground) holds no single circle over the
// slice's height, but each thin horizontal layer of it does. The stem is then the median of the
// layers' circles when at least half of the layers (two at least) hold one, every layer's
// centre lies within half that radius of the median centre and every layer's radius within a
// factor 2 of it: one trunk, layer above layer, not a limb and a twig curtain that happen to
// fit circles at different places, nor a clump of twigs that fits a 7 cm circle in one layer and
// a 26 cm one above it (a fig's low crown, 8.9 m from its trunk, passed for a stem on an open
// plot that way: docs/segment.md). Whether it stands
// upright is judged by the circles' centres: the layers of a thick trunk see different arcs
// (occlusion changes with height), so their points' centroids wander by up to a radius.
std::optional<Stem> fit_stem_by_layers(const PointCloud& cloud, const std::vector<int>& cluster, float low, float high,
                                       const SegmentOptions& options) {
    const int count = std::max(1, static_cast<int>(std::ceil((high - low) / options.stem_layer_height)));
    std::vector<std::vector<int>> layers(static_cast<std::size_t>(count));
    for (int i : cluster) {
        const float z = cloud.positions[static_cast<std::size_t>(i)].z();
        layers[static_cast<std::size_t>(std::min(count - 1, static_cast<int>((z - low) / options.stem_layer_height)))].push_back(i);
    }
    std::vector<CircleFit> circles;
    std::vector<Eigen::Vector3f> centres;  // of the circles, at their layers' mid-heights
    std::vector<int> on_circles;
    for (int k = 0; k < count; ++k) {
        const std::vector<int>& layer = layers[static_cast<std::size_t>(k)];
        if (static_cast<int>(layer.size()) < options.min_stem_points) continue;
        std::vector<Eigen::Vector2f> xy;
        for (int i : layer) xy.push_back(cloud.positions[static_cast<std::size_t>(i)].head<2>());
        const CircleFit circle = fit_circle(xy, options.circle_tolerance, options.min_stem_radius, options.max_stem_radius);
        if (!circle_holds(circle, layer.size(), options)) continue;
        circles.push_back(circle);
        centres.emplace_back(circle.centre.x(), circle.centre.y(), low + (static_cast<float>(k) + 0.5f) * options.stem_layer_height);
        for (std::size_t j = 0; j < layer.size(); ++j)
            if (std::abs((xy[j] - circle.centre).norm() - circle.radius) <= 2.0f * options.circle_tolerance) on_circles.push_back(layer[j]);
    }
    if (circles.size() < 2 || 2 * static_cast<int>(circles.size()) < count) return std::nullopt;
    const auto median = [&](auto value) {
        std::vector<float> values;
        for (const CircleFit& c : circles) values.push_back(value(c));
        std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
        return values[values.size() / 2];
    };
    Stem stem;
    stem.centre = {median([](const CircleFit& c) { return c.centre.x(); }), median([](const CircleFit& c) { return c.centre.y(); })};
    stem.radius = median([](const CircleFit& c) { return c.radius; });
    for (const CircleFit& c : circles) {
        if ((c.centre - stem.centre).norm() > 0.5f * stem.radius) return std::nullopt;  // one trunk, layer above layer
        if (c.radius > 2.0f * stem.radius || 2.0f * c.radius < stem.radius) return std::nullopt;  // ... of one girth
        stem.inliers += c.inliers;
    }
    if (!upright(centres, options.max_stem_lean)) return std::nullopt;
    stem.points = std::move(on_circles);
    return stem;
}

// A thin trunk followed up from the bottom of the slice, layer by layer, for as long as its
// layers hold circles of about one radius, each within a radius and the circle band of the one
// below (a leaning trunk moves by tan(lean) x the layer height between layers); two layers in a
// row that do not continue it end it. Where twigs and leaves start the layers hold other
// circles. nullopt unless the trunk is followed over `min_layers` layers.
std::optional<Stem> follow_trunk_up(const PointCloud& cloud, const std::vector<int>& cluster, float low, float high, int min_layers,
                                    const SegmentOptions& options) {
    const float height = options.trunk_layer_height;
    const int count = std::max(1, static_cast<int>(std::ceil((high - low) / height)));
    std::vector<std::vector<Eigen::Vector2f>> layers(static_cast<std::size_t>(count));
    std::vector<std::vector<int>> layer_points(static_cast<std::size_t>(count));
    for (int i : cluster) {
        const Eigen::Vector3f& p = cloud.positions[static_cast<std::size_t>(i)];
        const auto k = static_cast<std::size_t>(std::min(count - 1, static_cast<int>((p.z() - low) / height)));
        layers[k].push_back(p.head<2>());
        layer_points[k].push_back(i);
    }
    std::vector<CircleFit> run;
    Stem trunk;
    int missed = 0;  // layers in a row that did not continue the trunk
    for (std::size_t k = 0; k < layers.size() && missed < 2; ++k) {
        const CircleFit circle =
                static_cast<int>(layers[k].size()) < options.min_stem_points
                        ? CircleFit{}
                        : fit_circle(layers[k], options.circle_tolerance, options.min_stem_radius, options.max_stem_radius);
        bool continues = circle_holds(circle, layers[k].size(), options);
        if (continues && !run.empty()) {
            const CircleFit& below = run.back();
            const bool same_radius = circle.radius <= 1.5f * below.radius && below.radius <= 1.5f * circle.radius;
            continues = same_radius && (circle.centre - below.centre).norm() <= below.radius + options.circle_tolerance;
        }
        if (!continues) {
            missed += !run.empty();
            continue;
        }
        missed = 0;
        run.push_back(circle);
        for (std::size_t j = 0; j < layers[k].size(); ++j)
            if (std::abs((layers[k][j] - circle.centre).norm() - circle.radius) <= 2.0f * options.circle_tolerance)
                trunk.points.push_back(layer_points[k][j]);
    }
    if (static_cast<int>(run.size()) < min_layers) return std::nullopt;
    std::vector<float> radii;
    for (const CircleFit& c : run) {
        radii.push_back(c.radius);
        trunk.inliers += c.inliers;
    }
    std::nth_element(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(radii.size() / 2), radii.end());
    trunk.radius = radii[radii.size() / 2];
    trunk.centre = run.front().centre;
    return trunk;
}

// A slice cluster is a stem when it spans most of the slice height and a circle of a plausible
// radius holds enough of its points around enough of its circumference (Liang et al. 2012, §2.2),
// standing upright, over the slice's height or else layer by layer (a tapering trunk, or one
// whose visible arc turns with height).
std::optional<Stem> fit_stem(const PointCloud& cloud, const std::vector<float>& height_above_ground, const std::vector<int>& cluster,
                             const SegmentOptions& options) {
    if (static_cast<int>(cluster.size()) < options.min_stem_points) return std::nullopt;
    float low = std::numeric_limits<float>::infinity(), high = -low;
    std::vector<Eigen::Vector2f> xy;
    xy.reserve(cluster.size());
    for (int i : cluster) {
        const Eigen::Vector3f& p = cloud.positions[static_cast<std::size_t>(i)];
        xy.emplace_back(p.x(), p.y());
        low = std::min(low, p.z());
        high = std::max(high, p.z());
    }
    if (high - low < 0.5f * (options.stem_slice_high - options.stem_slice_low)) return std::nullopt;
    const CircleFit circle = fit_circle(xy, options.circle_tolerance, options.min_stem_radius, options.max_stem_radius);
    if (circle_holds(circle, cluster.size(), options)) {
        // Only the points on the circle seed the tree: a branch or a bush touching the stem in
        // the slice must win its points through the graph like any other.
        std::vector<int> on_circle;
        for (std::size_t k = 0; k < cluster.size(); ++k)
            if (std::abs((xy[k] - circle.centre).norm() - circle.radius) <= 2.0f * options.circle_tolerance) on_circle.push_back(cluster[k]);
        const std::vector<Eigen::Vector3f> samples = above_ground(cloud, height_above_ground, on_circle);
        if (upright(samples, options.max_stem_lean) && arc_in_every_upper_quarter(samples, circle.centre, options)) {
            // A thin trunk that leans (a crape myrtle's trunks part at 12-24 degrees) is smeared
            // over the slice's height, and with the twigs it carries it holds a circle several
            // times its radius; thin layers of it hold its own.
            const float quarter_slice = 0.25f * (options.stem_slice_high - options.stem_slice_low);
            const int min_layers = static_cast<int>(std::ceil(quarter_slice / options.trunk_layer_height));
            std::optional<Stem> trunk = follow_trunk_up(cloud, cluster, low, high, min_layers, options);
            if (trunk && trunk->radius < 0.5f * circle.radius) return trunk;
            return Stem{circle.centre, circle.radius, circle.inliers, std::move(on_circle)};
        }
    }
    // Points that lean may be a trunk whose visible arc turns with height (occlusion): its
    // layers' circles tell.
    return fit_stem_by_layers(cloud, cluster, low, high, options);
}

// Stems found in the slice that also have points under them down to the ground clearance, one
// per tree: arcs of one trunk split by occlusion give circles whose centres lie within each
// other, the one with more inliers stays; trunks closer than stem_merge_distance are one tree's,
// seeded from all of them and measured by the one with more inliers.
std::vector<Stem> find_stems(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                             const SegmentOptions& options) {
    std::vector<int> slice;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float h = terrain.height_above_ground[i];
        if (vegetation[i] && h >= options.stem_slice_low && h <= options.stem_slice_high) slice.push_back(static_cast<int>(i));
    }
    // Points between the graph's floor and the slice, flattened: a stem continues down to the
    // ground (within 1.5 radii: root flare), a branch or a drooping crown that crosses the slice
    // does not.
    std::vector<Eigen::Vector3f> below;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (vegetation[i] && terrain.height_above_ground[i] < options.stem_slice_low)
            below.emplace_back(cloud.positions[i].x(), cloud.positions[i].y(), 0.0f);
    if (below.empty()) return {};
    const KdTree below_index(below);
    std::vector<int> near;
    std::vector<float> squared;
    const auto reaches_ground = [&](const Stem& stem) {
        below_index.radius_search(Eigen::Vector3f(stem.centre.x(), stem.centre.y(), 0.0f),
                                  1.5f * stem.radius + 2.0f * options.circle_tolerance, near, squared,
                                  static_cast<std::size_t>(options.min_stem_points));
        return static_cast<int>(near.size()) >= options.min_stem_points;
    };
    std::vector<Stem> stems;
    const auto stem_of = [&](const std::vector<int>& cluster) {
        std::optional<Stem> stem = fit_stem(cloud, terrain.height_above_ground, cluster, options);
        return stem && reaches_ground(*stem) ? stem : std::nullopt;
    };
    for (const auto& cluster : cluster_slice(cloud, slice, options.stem_cluster_distance)) {
        if (auto stem = stem_of(cluster)) {
            stems.push_back(std::move(*stem));
            continue;
        }
        // A trunk inside a curtain of hanging twigs, or under limbs that fill the slice, joins
        // them at the cluster distance but not at a finer one.
        if (options.stem_subcluster_distance <= 0.0f || static_cast<int>(cluster.size()) < 2 * options.min_stem_points) continue;
        for (const auto& part : cluster_slice(cloud, cluster, options.stem_subcluster_distance))
            if (auto stem = stem_of(part)) stems.push_back(std::move(*stem));
    }
    std::stable_sort(stems.begin(), stems.end(), [](const Stem& a, const Stem& b) { return a.inliers > b.inliers; });
    std::vector<Stem> kept;
    std::vector<float> squared_radii;  // of each kept tree's trunks
    for (auto& stem : stems) {
        const bool duplicate = std::any_of(kept.begin(), kept.end(), [&](const Stem& k) {
            return (k.centre - stem.centre).norm() < std::max(k.radius, stem.radius) + options.circle_tolerance;
        });
        if (duplicate) continue;
        // A second trunk this close is the same tree's (a multi-stemmed tree, an arc of a
        // willow's curtain beside its trunk): its points seed that tree too.
        const auto same_tree = std::find_if(kept.begin(), kept.end(), [&](const Stem& k) {
            return (k.centre - stem.centre).norm() < options.stem_merge_distance;
        });
        if (same_tree != kept.end()) {
            // The trunks of one root collar are alike; a wider circle beside a trunk is an arc
            // of its curtain of twigs or a limb, which adds nothing to its cross-section.
            if (stem.radius <= 1.5f * same_tree->radius)
                squared_radii[static_cast<std::size_t>(same_tree - kept.begin())] += stem.radius * stem.radius;
            same_tree->points.insert(same_tree->points.end(), stem.points.begin(), stem.points.end());
        } else {
            squared_radii.push_back(stem.radius * stem.radius);
            kept.push_back(std::move(stem));
        }
    }
    // A multi-stemmed tree is as wide as the one stem of the same cross-section (its
    // equivalent diameter): sqrt(sum r^2).
    for (std::size_t k = 0; k < kept.size(); ++k) kept[k].radius = std::sqrt(squared_radii[k]);
    // Ids in a reproducible spatial order (south to north, then west to east).
    std::sort(kept.begin(), kept.end(), [](const Stem& a, const Stem& b) {
        return a.centre.y() != b.centre.y() ? a.centre.y() < b.centre.y() : a.centre.x() < b.centre.x();
    });
    return kept;
}

// Vegetation points thinned to a voxel grid: the graph is built on one point per voxel (the mean
// of its points) and every point takes its voxel's label.
struct Voxels {
    std::vector<Eigen::Vector3f> centres;
    std::vector<int> voxel_of_point;  // -1 for points outside the graph
};

Voxels voxelise(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation, float size) {
    Voxels voxels;
    voxels.voxel_of_point.assign(cloud.size(), -1);
    std::unordered_map<std::uint64_t, int> index;
    std::vector<Eigen::Vector3d> sums;
    std::vector<std::uint32_t> counts;
    const auto key_part = [size](float v) {
        return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v / size)) & 0x1FFFFF);
    };
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!vegetation[i]) continue;
        const Eigen::Vector3f& p = cloud.positions[i];
        const std::uint64_t key = key_part(p.x()) | key_part(p.y()) << 21 | key_part(p.z()) << 42;
        const auto [it, added] = index.emplace(key, static_cast<int>(sums.size()));
        if (added) {
            sums.emplace_back(0, 0, 0);
            counts.push_back(0);
        }
        sums[static_cast<std::size_t>(it->second)] += p.cast<double>();
        ++counts[static_cast<std::size_t>(it->second)];
        voxels.voxel_of_point[i] = it->second;
    }
    voxels.centres.reserve(sums.size());
    for (std::size_t v = 0; v < sums.size(); ++v) voxels.centres.push_back((sums[v] / counts[v]).cast<float>());
    return voxels;
}

// What the paths from each source cost per unit of the horizontal part of their edges' weights:
// (median stem radius / the source's stem radius)^exponent. A thick trunk carries a wide crown
// (crown width grows with the stem diameter), so its paths reach farther sideways than a thin
// neighbour's: the far limbs of a broad crown that reach over a small tree stay with their trunk
// instead of going to the stem that is nearer through the mixed branches (a multiplicatively
// weighted partition, Aurenhammer & Edelsbrunner 1984, in the graph's metric). Climbing is not
// scaled: a thin tree reaches its own top as cheaply as a thick one, whose paths would otherwise
// take the tops of tall, slender neighbours.
std::vector<float> reach_scales(const std::vector<Stem>& stems, const std::vector<int>& source_stem, float exponent) {
    std::vector<float> radii;
    for (const Stem& stem : stems) radii.push_back(stem.radius);
    std::nth_element(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(radii.size() / 2), radii.end());
    const float median_radius = radii[radii.size() / 2];
    std::vector<float> scales;
    scales.reserve(source_stem.size());
    for (int s : source_stem) scales.push_back(std::pow(median_radius / stems[static_cast<std::size_t>(s)].radius, exponent));
    return scales;
}

// Per edge of the graph, the horizontal share of its squared length: the part of its cost a
// stem's reach scales (a thick trunk's crown spreads wider, not higher).
std::vector<float> horizontal_shares(const NeighbourGraph& graph, const std::vector<Eigen::Vector3f>& positions) {
    std::vector<float> shares(graph.targets.size(), 0.0f);
    for (std::size_t u = 0; u + 1 < graph.offsets.size(); ++u)
        for (std::uint32_t e = graph.offsets[u]; e < graph.offsets[u + 1]; ++e) {
            const Eigen::Vector3f step = positions[static_cast<std::size_t>(graph.targets[e])] - positions[u];
            const float squared = step.squaredNorm();
            if (squared > 0.0f) shares[e] = std::clamp(step.head<2>().squaredNorm() / squared, 0.0f, 1.0f);
        }
    return shares;
}

// Lowest height above ground of each voxel's points.
std::vector<float> voxel_floors(const Voxels& voxels, const Terrain& terrain) {
    std::vector<float> floors(voxels.centres.size(), std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < voxels.voxel_of_point.size(); ++i) {
        const int v = voxels.voxel_of_point[i];
        if (v >= 0) floors[static_cast<std::size_t>(v)] = std::min(floors[static_cast<std::size_t>(v)], terrain.height_above_ground[i]);
    }
    return floors;
}

// Pieces of crown the paths do not reach join the tree nearest to them. The graph links each
// voxel to its k nearest only, so a sparse treetop or a tier of a tiered crown whose nearest
// voxels are all its own is a piece apart even within max_gap of the crown below it: on the
// synthetic terrestrial plots 25,000 tree points per plot stayed 0, most of them above 5 m,
// and the trees lost up to 7 m of their height. A piece that hangs in the air (its lowest point
// at least detached_min_height above the ground; understory stands on it) and has at least
// min_detached_voxels voxels (a stray return has one) takes the tree of the nearest labelled
// voxel within attach_gap; pieces attached in one round are labelled for the next, so a chain
// of pieces up a sparse top joins link by link.
void attach_detached_pieces(const NeighbourGraph& graph, const std::vector<Eigen::Vector3f>& centres,
                            const std::vector<float>& floors, const SegmentOptions& options, std::vector<int>& voxel_tree) {
    std::size_t piece_count = 0;
    const std::vector<int> piece = connected_components(graph, &piece_count);
    std::vector<std::vector<int>> unlabelled(piece_count);
    std::vector<float> piece_floor(piece_count, std::numeric_limits<float>::infinity());
    for (std::size_t v = 0; v < centres.size(); ++v) {
        if (voxel_tree[v] >= 0) continue;
        const auto p = static_cast<std::size_t>(piece[v]);
        unlabelled[p].push_back(static_cast<int>(v));
        piece_floor[p] = std::min(piece_floor[p], floors[v]);
    }
    std::vector<std::size_t> waiting;
    for (std::size_t p = 0; p < piece_count; ++p)
        if (unlabelled[p].size() >= static_cast<std::size_t>(options.min_detached_voxels) && piece_floor[p] >= options.detached_min_height)
            waiting.push_back(p);
    const float reach_squared = options.attach_gap * options.attach_gap;
    while (!waiting.empty()) {
        std::vector<Eigen::Vector3f> labelled_centres;
        std::vector<int> labelled_tree;
        for (std::size_t v = 0; v < centres.size(); ++v)
            if (voxel_tree[v] >= 0) {
                labelled_centres.push_back(centres[v]);
                labelled_tree.push_back(voxel_tree[v]);
            }
        if (labelled_centres.empty()) return;
        const KdTree labelled(labelled_centres);
        std::vector<std::pair<std::size_t, int>> joins;  // piece, tree
        std::vector<std::size_t> still_waiting;
        for (std::size_t p : waiting) {
            float best = reach_squared;
            int tree = -1;
            for (int v : unlabelled[p]) {
                float squared = 0.0f;
                const int nearest = labelled.nearest(centres[static_cast<std::size_t>(v)], &squared);
                if (squared <= best) {
                    best = squared;
                    tree = labelled_tree[static_cast<std::size_t>(nearest)];
                }
            }
            if (tree >= 0) joins.emplace_back(p, tree);
            else still_waiting.push_back(p);
        }
        if (joins.empty()) return;
        for (const auto& [p, tree] : joins)
            for (int v : unlabelled[p]) voxel_tree[static_cast<std::size_t>(v)] = tree;
        waiting = std::move(still_waiting);
    }
}

// Two trees' crowns do not share a top. A willow's curtain of hanging twigs can hold a circle of
// its trunk's size a little farther from the trunk than stem_merge_distance (1.1 m on a
// synthetic plot); the curtain's paths then take most of the crown, the trunk's the rest, and
// both regions reach the crown's top (their highest voxels 0.5 m apart). Stems closer than
// shared_top_stem_distance whose regions' highest voxels lie within shared_top_distance of each
// other are one tree's, which the stem with the most circle points keeps. Neighbours of one
// height do not meet so: on TreeLS's pine plot two pines 1.5 m apart have tops 0.7 m apart
// across but 1.6 m apart in height.
void join_trees_sharing_a_top(const std::vector<Stem>& stems, const std::vector<Eigen::Vector3f>& centres, const SegmentOptions& options,
                              std::vector<int>& voxel_tree) {
    if (options.shared_top_stem_distance <= 0.0f || stems.size() < 2) return;
    std::vector<int> highest(stems.size(), -1);
    for (std::size_t v = 0; v < voxel_tree.size(); ++v) {
        const int tree = voxel_tree[v];
        if (tree >= 0 && (highest[static_cast<std::size_t>(tree)] < 0 ||
                          centres[v].z() > centres[static_cast<std::size_t>(highest[static_cast<std::size_t>(tree)])].z()))
            highest[static_cast<std::size_t>(tree)] = static_cast<int>(v);
    }
    UnionFind joined(stems.size());
    bool any = false;
    for (std::size_t a = 0; a < stems.size(); ++a)
        for (std::size_t b = a + 1; b < stems.size(); ++b) {
            if (highest[a] < 0 || highest[b] < 0) continue;
            if ((stems[a].centre - stems[b].centre).norm() >= options.shared_top_stem_distance) continue;
            const Eigen::Vector3f& top_a = centres[static_cast<std::size_t>(highest[a])];
            const Eigen::Vector3f& top_b = centres[static_cast<std::size_t>(highest[b])];
            if ((top_a - top_b).norm() < options.shared_top_distance) any |= joined.unite(static_cast<int>(a), static_cast<int>(b));
        }
    if (!any) return;
    std::vector<int> keeper(stems.size(), -1);  // per set root: the stem with the most circle points
    for (std::size_t s = 0; s < stems.size(); ++s) {
        int& k = keeper[static_cast<std::size_t>(joined.find(static_cast<int>(s)))];
        if (k < 0 || stems[s].inliers > stems[static_cast<std::size_t>(k)].inliers) k = static_cast<int>(s);
    }
    for (int& tree : voxel_tree)
        if (tree >= 0) tree = keeper[static_cast<std::size_t>(joined.find(tree))];
}

void segment_terrestrial(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                         const SegmentOptions& options, TreeSegmentation& result) {
    const std::vector<Stem> stems = find_stems(cloud, terrain, vegetation, options);
    if (stems.empty()) return;
    const Voxels voxels = voxelise(cloud, vegetation, options.graph_voxel);

    // Every voxel of a stem's slice points is a source of that stem.
    std::vector<int> sources, source_stem;
    std::vector<std::uint8_t> is_source(voxels.centres.size(), 0);
    for (std::size_t s = 0; s < stems.size(); ++s)
        for (int i : stems[s].points) {
            const int v = voxels.voxel_of_point[static_cast<std::size_t>(i)];
            if (is_source[static_cast<std::size_t>(v)]) continue;
            is_source[static_cast<std::size_t>(v)] = 1;
            sources.push_back(v);
            source_stem.push_back(static_cast<int>(s));
        }

    NeighbourGraphOptions graph_options;
    graph_options.neighbours = std::min(options.graph_neighbours, std::max(2, static_cast<int>(voxels.centres.size()) - 1));
    graph_options.max_edge_length = options.max_gap;
    graph_options.join_components = false;  // a gap wider than max_gap separates: what lies beyond stays 0
    graph_options.beta = options.graph_beta;
    const NeighbourGraph graph = build_neighbour_graph(voxels.centres, graph_options);
    const std::vector<float> scales = reach_scales(stems, source_stem, options.stem_reach_exponent);
    const std::vector<float> shares = horizontal_shares(graph, voxels.centres);
    const ShortestPaths paths = shortest_paths(graph, sources, SourceScaling{scales, shares}, EdgeCost::Weight);

    std::vector<int> voxel_tree(voxels.centres.size(), -1);
    for (std::size_t v = 0; v < voxel_tree.size(); ++v)
        if (paths.source[v] >= 0) voxel_tree[v] = source_stem[static_cast<std::size_t>(paths.source[v])];
    if (options.attach_gap > 0.0f) attach_detached_pieces(graph, voxels.centres, voxel_floors(voxels, terrain), options, voxel_tree);
    join_trees_sharing_a_top(stems, voxels.centres, options, voxel_tree);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const int v = voxels.voxel_of_point[i];
        if (v >= 0 && voxel_tree[static_cast<std::size_t>(v)] >= 0) result.tree_id[i] = voxel_tree[static_cast<std::size_t>(v)] + 1;
    }
    std::vector<Eigen::Vector2f> stem_xy;
    std::vector<float> stem_radius;
    for (const auto& stem : stems) {
        stem_xy.push_back(stem.centre);
        stem_radius.push_back(stem.radius);
    }
    result.trees = collect_trees(cloud, terrain, result.tree_id, stems.size(), stem_xy, stem_radius, options.min_tree_height);
}

}  // namespace

const char* scan_mode_name(ScanMode mode) {
    switch (mode) {
        case ScanMode::Automatic:
            return "auto";
        case ScanMode::Airborne:
            return "als";
        case ScanMode::Terrestrial:
            return "tls";
    }
    return "auto";
}

ScanMode parse_scan_mode(std::string_view text) {
    if (text == "auto") return ScanMode::Automatic;
    if (text == "als") return ScanMode::Airborne;
    if (text == "tls") return ScanMode::Terrestrial;
    throw Error::usage("unknown scan mode '" + std::string(text) + "': expected auto, als or tls");
}

StandType parse_stand_type(std::string_view text) {
    if (text == "broadleaf") return StandType::Broadleaf;
    if (text == "conifer") return StandType::Conifer;
    throw Error::usage("unknown stand type '" + std::string(text) + "': expected broadleaf or conifer");
}

float airborne_reach(const SegmentOptions& options) { return 2.0f * (options.max_crown_radius + 3.0f * options.chm_smoothing); }

SegmentOptions with_stand_type(SegmentOptions options, StandType stand) {
    const SegmentOptions broadleaf;
    options.min_top_prominence = stand == StandType::Conifer ? 0.0f : broadleaf.min_top_prominence;
    options.top_prominence_ratio = stand == StandType::Conifer ? 0.0f : broadleaf.top_prominence_ratio;
    options.chm_smoothing = stand == StandType::Conifer ? 0.0f : broadleaf.chm_smoothing;
    options.max_crown_radius = stand == StandType::Conifer ? 3.5f : broadleaf.max_crown_radius;
    options.stem_reach_exponent = stand == StandType::Conifer ? 0.0f : broadleaf.stem_reach_exponent;
    return options;
}

float vegetation_return_spacing(const PointCloud& cloud, const Terrain& terrain, const SegmentOptions& options) {
    check_options(options);
    check_terrain_of(cloud, terrain);
    return return_spacing_of(cloud, vegetation_points(cloud, terrain, options.ground_clearance));
}

TreeSegmentation segment_trees(const PointCloud& cloud, const Terrain& terrain, const SegmentOptions& options) {
    check_options(options);
    check_terrain_of(cloud, terrain);
    TreeSegmentation result;
    result.tree_id.assign(cloud.size(), 0);
    const std::vector<std::uint8_t> vegetation = vegetation_points(cloud, terrain, options.ground_clearance);
    if (options.mode == ScanMode::Automatic) {
        result.mode_used = choose_mode(cloud, vegetation, options, result.mode_reason);
    } else {
        result.mode_used = options.mode;
        result.mode_reason = std::string("requested: ") + scan_mode_name(options.mode);
    }
    if (cloud.empty()) return result;
    if (result.mode_used == ScanMode::Terrestrial)
        segment_terrestrial(cloud, terrain, vegetation, options, result);
    else
        segment_airborne(cloud, terrain, vegetation, options, result);
    return result;
}

}  // namespace treelobes
