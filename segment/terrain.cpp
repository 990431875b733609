#include "segment/terrain.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/ransac_fit.hpp"
#include "render/image.hpp"

#include <Eigen/Cholesky>
#include <pcl/console/print.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/approximate_progressive_morphological_filter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <tuple>

namespace treelobes {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

void check_options(const TerrainOptions& o) {
    const auto positive = [](float v, const char* name) {
        if (!(v > 0.0f) || !std::isfinite(v)) throw Error::usage(std::string("terrain: ") + name + " must be > 0");
    };
    positive(o.cell_size, "cell size");
    positive(o.max_window_size, "max window size");
    positive(o.terrain_slope, "terrain slope");
    positive(o.initial_distance, "initial distance");
    positive(o.max_distance, "max distance");
    positive(o.ground_tolerance, "ground tolerance");
    positive(o.normalised_tolerance, "normalised tolerance");
}

void check_finite(const PointCloud& cloud) {
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (!cloud.positions[i].allFinite())
            throw Error::input("", "point " + std::to_string(i) +
                                           " has a non-finite coordinate (NaN or infinity); "
                                           "remove such points before terrain analysis");
}

bool is_noise(const PointCloud& cloud, std::size_t i) {
    if (cloud.classification.empty()) return false;
    return cloud.classification[i] == kAsprsLowNoise || cloud.classification[i] == kAsprsHighNoise;
}

// The grid covering the cloud's xy extent, all cells NaN.
DtmGrid empty_grid(const PointCloud& cloud, float cell) {
    const auto [low, high] = cloud.bounds();
    DtmGrid grid;
    grid.cell_size = cell;
    grid.origin = Eigen::Vector2d(std::floor(low.x() / cell) * cell, std::floor(low.y() / cell) * cell);
    grid.columns = static_cast<int>(std::floor((high.x() - grid.origin.x()) / cell)) + 1;
    grid.rows = static_cast<int>(std::floor((high.y() - grid.origin.y()) / cell)) + 1;
    grid.heights.assign(static_cast<std::size_t>(grid.columns) * grid.rows, kNaN);
    return grid;
}

std::size_t cell_of(const DtmGrid& grid, const Eigen::Vector3f& p) {
    const int c = std::clamp(static_cast<int>(std::floor((p.x() - grid.origin.x()) / grid.cell_size)), 0, grid.columns - 1);
    const int r = std::clamp(static_cast<int>(std::floor((p.y() - grid.origin.y()) / grid.cell_size)), 0, grid.rows - 1);
    return static_cast<std::size_t>(r) * grid.columns + c;
}

Eigen::Vector2f cell_centre(const DtmGrid& grid, std::size_t cell) {
    const auto c = static_cast<int>(cell % grid.columns), r = static_cast<int>(cell / grid.columns);
    return {static_cast<float>(grid.origin.x() + (c + 0.5) * grid.cell_size),
            static_cast<float>(grid.origin.y() + (r + 0.5) * grid.cell_size)};
}

// Index of the lowest non-noise point of every cell (-1 for cells without points).
std::vector<int> lowest_point_per_cell(const PointCloud& cloud, const DtmGrid& grid) {
    std::vector<int> lowest(grid.heights.size(), -1);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (is_noise(cloud, i)) continue;
        int& slot = lowest[cell_of(grid, cloud.positions[i])];
        if (slot < 0 || cloud.positions[i].z() < cloud.positions[static_cast<std::size_t>(slot)].z()) slot = static_cast<int>(i);
    }
    return lowest;
}

// A height-normalised tile (lidR's normalize_height) has its ground at global z = 0: the lowest
// points of at least half of the cells lie within the tolerance of 0 (5 m cells at least, so
// that under closed airborne canopy a cell still holds a ground return), and those lowest
// points show no slope (a real terrain crossing z = 0 puts half its cells near 0 too, but on an
// incline: a least-squares plane through them rises more than 1 in 50).
bool looks_normalised(const PointCloud& cloud, float cell_size, float tolerance) {
    constexpr float kDetectionCell = 5.0f;
    constexpr double kMaxGradient = 0.02;
    const DtmGrid grid = empty_grid(cloud, std::max(cell_size, kDetectionCell));
    std::size_t occupied = 0;
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d right = Eigen::Vector3d::Zero();
    for (int i : lowest_point_per_cell(cloud, grid)) {
        if (i < 0) continue;
        ++occupied;
        const Eigen::Vector3f& p = cloud.positions[static_cast<std::size_t>(i)];
        const double z = cloud.origin.z() + p.z();
        if (std::abs(z) > tolerance) continue;
        const Eigen::Vector3d row(1.0, p.x(), p.y());
        normal += row * row.transpose();
        right += row * z;
    }
    const auto near_zero = static_cast<std::size_t>(normal(0, 0));
    if (occupied == 0 || 2 * near_zero < occupied) return false;
    Eigen::LDLT<Eigen::Matrix3d> solver(normal);
    if (near_zero < 3 || solver.rcond() < 1e-9) return true;  // too few cells to see a slope
    const Eigen::Vector3d plane = solver.solve(right);
    return std::hypot(plane(1), plane(2)) <= kMaxGradient;
}

// Height at `at` from the nearest cells with data: a plane fitted to them by least squares
// weighted by inverse squared distance (exact on a slope, where plain inverse-distance
// weighting flattens a hole towards its rim), kept within the neighbours' height range widened by
// that range; inverse-distance weighting when the neighbours are collinear.
float interpolate_from_neighbours(const Eigen::Vector2f& at, const std::vector<Eigen::Vector3f>& known, const std::vector<float>& values,
                                  const std::vector<int>& near, const std::vector<float>& squared) {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d right = Eigen::Vector3d::Zero();
    double idw_sum = 0, idw_weights = 0;
    float low = std::numeric_limits<float>::infinity(), high = -low;
    for (std::size_t j = 0; j < near.size(); ++j) {
        const auto k = static_cast<std::size_t>(near[j]);
        const double w = 1.0 / std::max(1e-6, static_cast<double>(squared[j]));
        const Eigen::Vector3d row(1.0, known[k].x() - at.x(), known[k].y() - at.y());
        normal += w * row * row.transpose();
        right += w * row * values[k];
        idw_sum += w * values[k];
        idw_weights += w;
        low = std::min(low, values[k]);
        high = std::max(high, values[k]);
    }
    const double idw = idw_sum / idw_weights;
    Eigen::LDLT<Eigen::Matrix3d> solver(normal);
    if (near.size() < 3 || solver.rcond() < 1e-6) return static_cast<float>(idw);
    const double plane = solver.solve(right)(0);  // the plane's height at `at` (offsets are relative to it)
    const float spread = high - low;
    return std::clamp(static_cast<float>(plane), low - spread, high + spread);
}

// Every empty cell is filled from the nearest cells that hold data, so the DTM has no holes
// inside (or around) the ground that was seen.
void fill_empty_cells(DtmGrid& grid) {
    std::vector<Eigen::Vector3f> known;
    std::vector<float> values;
    for (std::size_t c = 0; c < grid.heights.size(); ++c)
        if (std::isfinite(grid.heights[c])) {
            const Eigen::Vector2f xy = cell_centre(grid, c);
            known.emplace_back(xy.x(), xy.y(), 0.0f);
            values.push_back(grid.heights[c]);
        }
    if (known.empty() || known.size() == grid.heights.size()) return;
    const KdTree index(known);
    constexpr int kNeighbours = 12;
    std::vector<int> near;
    std::vector<float> squared;
    for (std::size_t c = 0; c < grid.heights.size(); ++c) {
        if (std::isfinite(grid.heights[c])) continue;
        const Eigen::Vector2f xy = cell_centre(grid, c);
        const Eigen::Vector3f query(xy.x(), xy.y(), 0.0f);
        index.knn(query, kNeighbours, near, squared);
        // On a grid many cells lie at the same distance: take every cell as near as the k-th and
        // order them by distance, then position, so that the height does not depend on how the
        // index broke ties (another tile extent, the same ground, gives the same DTM).
        index.radius_search(query, std::sqrt(squared.back()) * 1.0001f + 1e-6f, near, squared);
        std::vector<std::size_t> order(near.size());
        std::iota(order.begin(), order.end(), std::size_t{0});
        std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            const Eigen::Vector3f &pa = known[static_cast<std::size_t>(near[a])], &pb = known[static_cast<std::size_t>(near[b])];
            return std::make_tuple(squared[a], pa.x(), pa.y()) < std::make_tuple(squared[b], pb.x(), pb.y());
        });
        std::vector<int> sorted_near;
        std::vector<float> sorted_squared;
        for (std::size_t k : order) {
            sorted_near.push_back(near[k]);
            sorted_squared.push_back(squared[k]);
        }
        grid.heights[c] = interpolate_from_neighbours(xy, known, values, sorted_near, sorted_squared);
    }
}

// Height of every cell at its centre from the flagged points in it: a least-squares plane
// through them where they span the cell (on a slope the mean of a few points sits where they
// happen to lie, not at the centre), their mean otherwise; NaN where a cell holds none. Then
// the empty cells are filled.
DtmGrid ground_height_grid(const PointCloud& cloud, const DtmGrid& shape, const std::vector<std::uint8_t>& use) {
    DtmGrid grid = shape;
    std::vector<Eigen::Matrix3d> normal(grid.heights.size(), Eigen::Matrix3d::Zero());
    std::vector<Eigen::Vector3d> right(grid.heights.size(), Eigen::Vector3d::Zero());
    std::vector<float> low(grid.heights.size(), std::numeric_limits<float>::infinity());
    std::vector<float> high(grid.heights.size(), -std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!use[i]) continue;
        const Eigen::Vector3f& p = cloud.positions[i];
        const std::size_t c = cell_of(grid, p);
        const Eigen::Vector2f centre = cell_centre(grid, c);
        const Eigen::Vector3d row(1.0, p.x() - centre.x(), p.y() - centre.y());
        normal[c] += row * row.transpose();
        right[c] += row * static_cast<double>(p.z());
        low[c] = std::min(low[c], p.z());
        high[c] = std::max(high[c], p.z());
    }
    for (std::size_t c = 0; c < grid.heights.size(); ++c) {
        const double count = normal[c](0, 0);
        if (count == 0) continue;
        const double mean = right[c](0) / count;
        Eigen::LDLT<Eigen::Matrix3d> solver(normal[c]);
        if (count < 4 || solver.rcond() < 1e-4) {
            grid.heights[c] = static_cast<float>(mean);
            continue;
        }
        const float spread = high[c] - low[c];
        grid.heights[c] = std::clamp(static_cast<float>(solver.solve(right[c])(0)), low[c] - 0.5f * spread, high[c] + 0.5f * spread);
    }
    fill_empty_cells(grid);
    return grid;
}

// Points within `below` under and `above` over the surface.
std::vector<std::uint8_t> points_near_surface(const PointCloud& cloud, const DtmGrid& surface, float below, float above) {
    std::vector<std::uint8_t> near(cloud.size(), 0);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (is_noise(cloud, i)) continue;
        const Eigen::Vector3f& p = cloud.positions[i];
        const float dz = p.z() - surface.height_at(p.x(), p.y());
        near[i] = dz >= -below && dz <= above;
    }
    return near;
}

// A cell whose lowest point lies far below the median of its neighbours' lowest points holds a
// low outlier (multipath, a bird under the sensor): the morphological opening would keep it as
// ground, so it is left out and the cell filled from its neighbours.
void drop_low_outliers(const PointCloud& cloud, const DtmGrid& grid, std::vector<int>& lowest, float drop) {
    std::vector<int> kept = lowest;
    std::vector<float> around;
    for (int r = 0; r < grid.rows; ++r)
        for (int c = 0; c < grid.columns; ++c) {
            const std::size_t cell = static_cast<std::size_t>(r) * grid.columns + c;
            if (lowest[cell] < 0) continue;
            around.clear();
            for (int dr = -1; dr <= 1; ++dr)
                for (int dc = -1; dc <= 1; ++dc) {
                    const int rr = r + dr, cc = c + dc;
                    if ((dr == 0 && dc == 0) || rr < 0 || cc < 0 || rr >= grid.rows || cc >= grid.columns) continue;
                    const int j = lowest[static_cast<std::size_t>(rr) * grid.columns + cc];
                    if (j >= 0) around.push_back(cloud.positions[static_cast<std::size_t>(j)].z());
                }
            if (around.size() < 3) continue;
            std::nth_element(around.begin(), around.begin() + around.size() / 2, around.end());
            if (cloud.positions[static_cast<std::size_t>(lowest[cell])].z() < around[around.size() / 2] - drop) kept[cell] = -1;
        }
    lowest.swap(kept);
}

// Zhang et al. 2003 (§2.2) on the cells' lowest points, as PCL's grid version implements it.
// The points are first detrended by a robust plane: the opening of a square window cuts the
// upslope edge of a steep tile by up to slope x half-window, far beyond the height thresholds.
std::vector<int> ground_cells_by_morphological_filter(const PointCloud& cloud, const std::vector<int>& lowest,
                                                      const TerrainOptions& options) {
    std::vector<int> cells;
    std::vector<Eigen::Vector3f> points;
    for (std::size_t c = 0; c < lowest.size(); ++c)
        if (lowest[c] >= 0) {
            cells.push_back(static_cast<int>(c));
            points.push_back(cloud.positions[static_cast<std::size_t>(lowest[c])]);
        }
    if (points.size() < 3) return cells;
    const PlaneFit plane = fit_plane(points, 2.0f * options.max_distance, 1000, 60.0f);
    pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
    auto detrended = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    detrended->reserve(points.size());
    for (const auto& p : points) {
        const float trend = plane.ok ? -(plane.normal.x() * p.x() + plane.normal.y() * p.y() + plane.offset) / plane.normal.z() : 0.0f;
        detrended->push_back(pcl::PointXYZ(p.x(), p.y(), p.z() - trend));
    }
    pcl::ApproximateProgressiveMorphologicalFilter<pcl::PointXYZ> filter;
    filter.setInputCloud(detrended);
    filter.setCellSize(options.cell_size);
    filter.setMaxWindowSize(std::max(1, static_cast<int>(std::ceil(options.max_window_size / options.cell_size))));
    filter.setSlope(options.terrain_slope);
    filter.setInitialDistance(options.initial_distance);
    filter.setMaxDistance(options.max_distance);
    filter.setNumberOfThreads(1);  // deterministic and frugal; the grid is small
    pcl::Indices kept;
    filter.extract(kept);
    std::vector<int> ground;
    ground.reserve(kept.size());
    for (auto k : kept) ground.push_back(cells[static_cast<std::size_t>(k)]);
    std::sort(ground.begin(), ground.end());
    return ground;
}

// Ground of an unclassified tile: the filter's ground cells give a first surface; the points
// near it give a second, better one (a cell's lowest point sits at its downhill corner on a
// slope), and the points near that one are the ground.
std::vector<std::uint8_t> filter_ground(const PointCloud& cloud, const DtmGrid& shape, std::vector<int> lowest,
                                        const TerrainOptions& options) {
    drop_low_outliers(cloud, shape, lowest, 1.0f + options.terrain_slope * options.cell_size);
    DtmGrid first = shape;
    for (int cell : ground_cells_by_morphological_filter(cloud, lowest, options))
        first.heights[static_cast<std::size_t>(cell)] =
                cloud.positions[static_cast<std::size_t>(lowest[static_cast<std::size_t>(cell)])].z();
    fill_empty_cells(first);
    const float band = options.ground_tolerance + 0.5f * options.terrain_slope * options.cell_size;
    const DtmGrid second = ground_height_grid(cloud, shape, points_near_surface(cloud, first, options.ground_tolerance, band));
    return points_near_surface(cloud, second, options.ground_tolerance, options.ground_tolerance);
}

std::size_t count_ground(const std::vector<std::uint8_t>& ground) {
    return static_cast<std::size_t>(std::count(ground.begin(), ground.end(), std::uint8_t{1}));
}

void fill_heights_above_ground(const PointCloud& cloud, Terrain& terrain) {
    terrain.height_above_ground.resize(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3f& p = cloud.positions[i];
        terrain.height_above_ground[i] = p.z() - terrain.dtm.height_at(p.x(), p.y());
    }
}

}  // namespace

float DtmGrid::height_at(float x, float y) const {
    if (heights.empty()) return kNaN;
    // Bilinear between cell centres; outside the outermost centres the edge cells hold.
    const double fx = std::clamp((x - origin.x()) / cell_size - 0.5, 0.0, static_cast<double>(columns - 1));
    const double fy = std::clamp((y - origin.y()) / cell_size - 0.5, 0.0, static_cast<double>(rows - 1));
    const int c0 = static_cast<int>(std::floor(fx)), r0 = static_cast<int>(std::floor(fy));
    const int c1 = std::min(c0 + 1, columns - 1), r1 = std::min(r0 + 1, rows - 1);
    const double tx = fx - c0, ty = fy - r0;
    const double corner_weight[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
    const float corner_height[4] = {at(c0, r0), at(c1, r0), at(c0, r1), at(c1, r1)};
    double sum = 0, weights = 0;
    for (int k = 0; k < 4; ++k)
        if (std::isfinite(corner_height[k])) {
            sum += corner_weight[k] * corner_height[k];
            weights += corner_weight[k];
        }
    return weights > 0 ? static_cast<float>(sum / weights) : kNaN;
}

float grid_cell_for_points(const PointCloud& cloud, float cell) {
    if (cloud.empty()) return cell;
    const auto [low, high] = cloud.bounds();
    const double area = static_cast<double>(high.x() - low.x()) * static_cast<double>(high.y() - low.y());
    return std::max(cell, static_cast<float>(std::sqrt(area / (4.0 * static_cast<double>(cloud.size())))));
}

Terrain analyse_terrain(const PointCloud& cloud, const TerrainOptions& requested) {
    check_options(requested);
    TerrainOptions options = requested;
    options.cell_size = grid_cell_for_points(cloud, requested.cell_size);
    Terrain terrain;
    if (cloud.empty()) {
        terrain.ground_source = "none";
        return terrain;
    }
    cloud.check_consistent("terrain");
    check_finite(cloud);
    const DtmGrid shape = empty_grid(cloud, options.cell_size);
    std::vector<int> lowest = lowest_point_per_cell(cloud, shape);

    const bool has_ground_class =
            options.use_classification && !cloud.classification.empty() &&
            std::find(cloud.classification.begin(), cloud.classification.end(), kAsprsGround) != cloud.classification.end();
    if (looks_normalised(cloud, options.cell_size, options.normalised_tolerance)) {
        terrain.ground_source = "normalised";
        terrain.dtm = shape;
        std::fill(terrain.dtm.heights.begin(), terrain.dtm.heights.end(), static_cast<float>(-cloud.origin.z()));
        terrain.is_ground.resize(cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i)
            terrain.is_ground[i] = has_ground_class ? cloud.classification[i] == kAsprsGround
                                                    : !is_noise(cloud, i) && std::abs(cloud.origin.z() + cloud.positions[i].z()) <=
                                                                                     options.ground_tolerance;
    } else if (has_ground_class) {
        terrain.ground_source = "classified";
        terrain.is_ground.resize(cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i) terrain.is_ground[i] = cloud.classification[i] == kAsprsGround;
        terrain.dtm = ground_height_grid(cloud, shape, terrain.is_ground);
    } else {
        terrain.ground_source = "filtered";
        terrain.is_ground = filter_ground(cloud, shape, std::move(lowest), options);
        terrain.dtm = ground_height_grid(cloud, shape, terrain.is_ground);
    }
    terrain.ground_points = count_ground(terrain.is_ground);
    if (terrain.ground_points == 0 && terrain.ground_source != "normalised")
        throw Error::input("", "no ground points found (" + std::to_string(cloud.size()) +
                                       " points); a tile needs some ground to measure heights from");
    fill_heights_above_ground(cloud, terrain);
    return terrain;
}

void write_ascii_grid(const DtmGrid& dtm, const Eigen::Vector3d& origin, const std::filesystem::path& path) {
    if (dtm.empty()) throw Error::input(path.string(), "no terrain grid to write (empty tile)");
    write_atomically(path, [&](std::ostream& out) {
        char line[128];
        std::snprintf(line, sizeof line, "ncols %d\nnrows %d\nxllcorner %.3f\nyllcorner %.3f\ncellsize %.6g\nNODATA_value -9999\n",
                      dtm.columns, dtm.rows, origin.x() + dtm.origin.x(), origin.y() + dtm.origin.y(), dtm.cell_size);
        out << line;
        // ESRI grids list the northernmost row first.
        for (int r = dtm.rows - 1; r >= 0; --r) {
            for (int c = 0; c < dtm.columns; ++c) {
                const float h = dtm.at(c, r);
                if (std::isfinite(h))
                    std::snprintf(line, sizeof line, "%s%.3f", c ? " " : "", origin.z() + h);
                else
                    std::snprintf(line, sizeof line, "%s-9999", c ? " " : "");
                out << line;
            }
            out << '\n';
        }
    });
}

void write_hillshade_png(const DtmGrid& dtm, const std::filesystem::path& path) {
    if (dtm.empty()) throw Error::input(path.string(), "no terrain grid to write (empty tile)");
    // Horn's (1981) slope and aspect from the 3 x 3 neighbourhood, lit from azimuth 315 degrees,
    // 45 degrees above the horizon (the GDAL/ESRI default hillshade).
    const double zenith = std::numbers::pi / 4, azimuth = 315.0 * std::numbers::pi / 180.0;
    const auto height = [&](int c, int r) {
        const float h = dtm.at(std::clamp(c, 0, dtm.columns - 1), std::clamp(r, 0, dtm.rows - 1));
        return std::isfinite(h) ? static_cast<double>(h) : 0.0;
    };
    render::Image image(dtm.columns, dtm.rows, {0, 0, 0, 255});
    for (int r = 0; r < dtm.rows; ++r)
        for (int c = 0; c < dtm.columns; ++c) {
            if (!std::isfinite(dtm.at(c, r))) continue;
            // Row index grows northwards; x east.
            const double dzdx = ((height(c + 1, r + 1) + 2 * height(c + 1, r) + height(c + 1, r - 1)) -
                                 (height(c - 1, r + 1) + 2 * height(c - 1, r) + height(c - 1, r - 1))) /
                                (8 * dtm.cell_size);
            const double dzdy = ((height(c - 1, r + 1) + 2 * height(c, r + 1) + height(c + 1, r + 1)) -
                                 (height(c - 1, r - 1) + 2 * height(c, r - 1) + height(c + 1, r - 1))) /
                                (8 * dtm.cell_size);
            const double slope = std::atan(std::hypot(dzdx, dzdy));
            // Aspect as the compass direction the slope faces (0 = north, clockwise).
            const double aspect = std::atan2(-dzdx, -dzdy);
            const double light = std::cos(zenith) * std::cos(slope) + std::sin(zenith) * std::sin(slope) * std::cos(azimuth - aspect);
            const auto grey = static_cast<std::uint8_t>(std::clamp(std::lround(255.0 * light), 0L, 255L));
            image.set(c, dtm.rows - 1 - r, {grey, grey, grey, 255});
        }
    render::write_png(image, path);
}

}  // namespace treelobes
