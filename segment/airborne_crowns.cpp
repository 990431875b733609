#include "segment/airborne_crowns.hpp"

#include "geometry/union_find.hpp"
#include "segment/tree_labels.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <tuple>

namespace treelobes {

namespace {

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

// The CHM's cell and discs grow with the returns' spacing (and the cell as for the DTM where the
// points are too few for the tile's extent). At 1-2 pulses per m^2 (many national surveys) 0.15 m
// discs on 0.5 m cells leave most cells empty, every return stands alone as a local maximum, and
// synthetic tiles with 25 trees gave 100-380 "trees" each (docs/segment.md).
// In a sparse survey the spacing reads short, and discs of s/sqrt(2) leave the crowns in pieces
// that no pass joins; discs of the whole spacing close them, coarser cells would not.
SegmentOptions with_chm_grid_for_spacing(const PointCloud& cloud, SegmentOptions options, float spacing) {
    options.chm_cell = grid_cell_for_points(cloud, std::max(options.chm_cell, options.cell_per_spacing * spacing));
    const bool sparse = spacing > kSparseSurveyReturnSpacing && options.disc_per_spacing > 0.0f;
    options.point_radius = std::max(options.point_radius, (sparse ? options.sparse_disc_per_spacing : options.disc_per_spacing) * spacing);
    return options;
}

}  // namespace

float return_spacing_of(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation) {
    const double density = occupied_cells(cloud, vegetation, 2.0f).density(2.0);
    return density > 0.0 ? static_cast<float>(1.0 / std::sqrt(density)) : 0.0f;
}

float survey_pulse_density(const PointCloud& cloud) {
    std::vector<std::uint8_t> first_return(cloud.size(), 1);
    if (cloud.return_number.size() == cloud.size())
        for (std::size_t i = 0; i < cloud.size(); ++i) first_return[i] = cloud.return_number[i] <= 1;
    constexpr float kFootprintCell = 10.0f;
    const OccupiedCells cells = occupied_cells(cloud, first_return, kFootprintCell);
    if (!cells.points) return 0.0f;
    Eigen::AlignedBox3f box;
    for (const Eigen::Vector3f& p : cloud.positions) box.extend(p);
    const double box_area = std::max(static_cast<double>(box.sizes().x()) * box.sizes().y(), 1.0);
    const double cell_area = static_cast<double>(cells.cells) * kFootprintCell * kFootprintCell;
    // Cells that hold one or two pulses each cannot show the footprint's gaps, nor a density below 0.01-0.02.
    const bool sparse_cells = cells.points < 2 * cells.cells;
    return static_cast<float>(static_cast<double>(cells.points) / (sparse_cells ? box_area : std::min(box_area, cell_area)));
}

void segment_airborne(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                      const SegmentOptions& requested, TreeSegmentation& result) {
    result.return_spacing = requested.return_spacing > 0.0f ? requested.return_spacing : return_spacing_of(cloud, vegetation);
    result.pulse_density = survey_pulse_density(cloud);
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

}  // namespace treelobes
