// Feature groups computed directly from the points in the tree frame: overall shape and stem,
// vertical distribution, radial crown profile, horizontal shape, structure (occupancy,
// inhomogeneity, box counting). See docs/features.md for the list.
#include "classify/feature_groups.hpp"
#include "geometry/ransac_fit.hpp"
#include "geometry/union_find.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <complex>
#include <optional>
#include <unordered_map>
#include <numbers>

namespace treelobes::classify::detail {

namespace {

constexpr int kProfileLayers = 15;    // radial profile layers
constexpr int kCrownBaseLayers = 50;  // layers scanned for the crown base
constexpr int kHeightBins = 20;
constexpr int kRadialBins = 10;
constexpr int kCrownSectors = 8;

// Indices of voxel points whose relative height lies in [lo, hi).
std::vector<std::size_t> layer(const TreeFrame& f, double lo, double hi) {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < f.points.size(); ++i)
        if (f.rel_height[i] >= lo && (f.rel_height[i] < hi || (hi >= 1.0 && f.rel_height[i] <= 1.0))) out.push_back(i);
    return out;
}

// Groups of 2-D points linked by distances below `eps` (grid hashing); returns the group sizes.
std::vector<int> cluster_sizes_2d(const std::vector<Eigen::Vector2f>& pts, float eps) {
    UnionFind sets(pts.size());
    auto key = [](long gx, long gy) { return (gx << 32) ^ (gy & 0xffffffffL); };
    std::unordered_map<long, std::vector<int>> grid;
    for (std::size_t i = 0; i < pts.size(); ++i)
        grid[key(std::lround(std::floor(pts[i].x() / eps)), std::lround(std::floor(pts[i].y() / eps)))].push_back(static_cast<int>(i));
    for (std::size_t i = 0; i < pts.size(); ++i) {
        const long gx = std::lround(std::floor(pts[i].x() / eps)), gy = std::lround(std::floor(pts[i].y() / eps));
        for (long dx = -1; dx <= 1; ++dx)
            for (long dy = -1; dy <= 1; ++dy) {
                const auto it = grid.find(key(gx + dx, gy + dy));
                if (it == grid.end()) continue;
                for (int j : it->second)
                    if ((pts[i] - pts[j]).squaredNorm() < eps * eps) sets.unite(static_cast<int>(i), j);
            }
    }
    std::vector<int> sizes;
    for (std::size_t i = 0; i < pts.size(); ++i)
        if (sets.find(static_cast<int>(i)) == static_cast<int>(i)) sizes.push_back(sets.set_size(static_cast<int>(i)));
    return sizes;
}

// Stems crossing the layer [h - 0.02, h + 0.02] H: connected groups of voxel points (link
// distance 2.5 voxels) holding at least 5 % of the layer and 3 points.
int stem_count(const TreeFrame& f, double h) {
    std::vector<Eigen::Vector2f> pts;
    for (auto i : layer(f, h - 0.02, h + 0.02)) pts.push_back(f.points[i].head<2>());
    if (pts.size() < 3) return 0;
    int count = 0;
    for (int n : cluster_sizes_2d(pts, 2.5f * f.voxel)) count += n >= 3 && n >= 0.05 * static_cast<double>(pts.size());
    return count;
}

// Stem diameter at breast height (1.1-1.5 m; 15-25 % of the height for trees under 6 m) from a
// least-squares (Kasa) circle through the raw points near the axis; falls back on twice the
// median distance to their centre when the fit is implausible; 0 when too few points (airborne).
float trunk_diameter(const TreeFrame& f) {
    const bool small = f.height < 6.0f;
    const float lo = small ? 0.15f * f.height : 1.1f, hi = small ? 0.25f * f.height : 1.5f;
    const float reach = std::max(0.25f, std::min(1.0f, 0.35f * f.crown_radius));
    std::vector<Eigen::Vector2f> pts;
    for (const auto& p : f.raw)
        if (p.z() >= lo && p.z() < hi && p.head<2>().norm() < reach) pts.push_back(p.head<2>());
    if (pts.size() < 8) return 0.0f;
    std::vector<Eigen::Vector2d> slice(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) slice[i] = pts[i].cast<double>();
    const std::optional<Circle2d> circle = fit_circle_least_squares(slice);
    if (circle && circle->radius < reach && circle->centre.norm() < reach) return static_cast<float>(2 * circle->radius);
    Eigen::Vector2f mean = Eigen::Vector2f::Zero();
    for (const auto& p : pts) mean += p;
    mean /= static_cast<float>(pts.size());
    std::vector<float> d;
    for (const auto& p : pts) d.push_back((p - mean).norm());
    return 2.0f * quantile(d, 0.5);
}

// Per crown-base layer (kCrownBaseLayers over the height), the 90 % radius (0 for < 3 points).
std::vector<float> layer_r90(const TreeFrame& f, int layers) {
    std::vector<std::vector<float>> r(layers);
    for (std::size_t i = 0; i < f.points.size(); ++i)
        r[std::min(layers - 1, static_cast<int>(f.rel_height[i] * layers))].push_back(f.radius[i]);
    std::vector<float> out(layers, 0.0f);
    for (int k = 0; k < layers; ++k)
        if (r[k].size() >= 3) out[k] = quantile(r[k], 0.9);
    return out;
}

}  // namespace

// ---------------------------------------------------------------- shape
void describe_shape(Catalogue& c) {
    c.add("height", "m", "H: 99.9 % quantile of the voxel points' z above the ground");
    c.add("crown_radius", "m", "R: 95 % quantile of the horizontal distance r to the stem axis");
    c.add("crown_width_major", "m", "extent along the major horizontal axis (98 % minus 2 % quantile of x)");
    c.add("crown_width_minor", "m", "extent along the minor horizontal axis (98 % minus 2 % quantile of y)");
    c.add("width_height_ratio", "1", "mean of the two crown widths divided by H");
    c.add("crown_elongation", "1", "minor over major crown width");
    c.add("trunk_diameter", "m",
          "stem diameter at 1.1-1.5 m (15-25 % of H below 6 m): least-squares circle through the raw points near the axis; 0 when no stem "
          "is visible");
    c.add("trunk_diameter_ratio", "1", "trunk_diameter / H");
    c.add("crown_base_height", "m",
          "trunk height: bottom of the lowest of 50 layers whose 90 % radius exceeds max(2.5 trunk radius, 0.25 R)");
    c.add("crown_base_ratio", "1", "crown_base_height / H");
    c.add("widest_layer_height", "1", "relative height of the layer (of 50) with the largest 90 % radius");
    c.add("stems_at_05", "count",
          "main stems at 5 % of H: connected groups (link 2.5 voxels) of the layer's voxel points with >= 5 % of them");
    c.add("stems_at_10", "count", "main stems at 10 % of H (as stems_at_05)");
    c.add("stems_at_20", "count", "main stems at 20 % of H (as stems_at_05)");
    c.add("crown_offset_ratio", "1", "horizontal distance from the axis to the centroid of the points above the crown base, / R");
    c.add("outer_fraction", "1", "fraction of voxel points with r > 0.5 R");
}

void compute_shape(TreeFrame& f, FeatureSink& out) {
    std::vector<float> x, y;
    for (const auto& p : f.points) x.push_back(p.x()), y.push_back(p.y());
    const float major = quantile(x, 0.98) - quantile(x, 0.02), minor = quantile(y, 0.98) - quantile(y, 0.02);
    f.trunk_diameter = trunk_diameter(f);
    const auto r90 = layer_r90(f, kCrownBaseLayers);
    const float limit = std::max(1.25f * f.trunk_diameter, 0.25f * f.crown_radius);
    int base_layer = 0;
    while (base_layer < kCrownBaseLayers - 1 && r90[base_layer] <= limit) ++base_layer;
    f.crown_base = f.height * static_cast<float>(base_layer) / kCrownBaseLayers;
    const int widest = static_cast<int>(std::max_element(r90.begin(), r90.end()) - r90.begin());
    Eigen::Vector2f centroid = Eigen::Vector2f::Zero();
    int crown_points = 0, outer = 0;
    for (std::size_t i = 0; i < f.points.size(); ++i) {
        if (f.points[i].z() >= f.crown_base) centroid += f.points[i].head<2>(), ++crown_points;
        outer += f.radius[i] > 0.5f * f.crown_radius;
    }
    if (crown_points > 0) centroid /= static_cast<float>(crown_points);

    out.add("height", f.height);
    out.add("crown_radius", f.crown_radius);
    out.add("crown_width_major", major);
    out.add("crown_width_minor", minor);
    out.add("width_height_ratio", 0.5 * (major + minor) / f.height);
    out.add("crown_elongation", major > 0 ? minor / major : 0.0);
    out.add("trunk_diameter", f.trunk_diameter);
    out.add("trunk_diameter_ratio", f.trunk_diameter / f.height);
    out.add("crown_base_height", f.crown_base);
    out.add("crown_base_ratio", f.crown_base / f.height);
    out.add("widest_layer_height", (widest + 0.5) / kCrownBaseLayers);
    out.add("stems_at_05", stem_count(f, 0.05));
    out.add("stems_at_10", stem_count(f, 0.10));
    out.add("stems_at_20", stem_count(f, 0.20));
    out.add("crown_offset_ratio", centroid.norm() / f.crown_radius);
    out.add("outer_fraction", static_cast<double>(outer) / static_cast<double>(f.points.size()));
}

// ---------------------------------------------------------------- vertical
void describe_vertical(Catalogue& c) {
    for (int k = 0; k < kHeightBins; ++k)
        c.add(indexed("zhist", k), "1",
              "fraction of voxel points with relative height h in [" + std::to_string(k * 5) + ", " + std::to_string(k * 5 + 5) + ") %");
    for (int k = 1; k <= 9; ++k) c.add(indexed("z_decile", k), "1", std::to_string(k * 10) + " % quantile of h");
    c.add("z_mean", "1", "mean of the relative heights h");
    c.add("z_sd", "1", "standard deviation of h");
    c.add("z_moment2", "1", "second central moment of h (vertical density distribution)");
    c.add("z_moment3", "1", "third central moment of h");
    c.add("z_moment4", "1", "fourth central moment of h");
    c.add("z_skewness", "1", "third central moment / sd^3");
    c.add("z_kurtosis", "1", "fourth central moment / sd^4");
}

void compute_vertical(const TreeFrame& f, FeatureSink& out) {
    std::vector<double> hist(kHeightBins, 0.0);
    for (float h : f.rel_height) hist[std::min(kHeightBins - 1, static_cast<int>(h * kHeightBins))] += 1.0;
    for (int k = 0; k < kHeightBins; ++k) out.add(indexed("zhist", k), hist[k] / static_cast<double>(f.points.size()));
    for (int k = 1; k <= 9; ++k) out.add(indexed("z_decile", k), quantile(f.rel_height, k / 10.0));
    const Moments m = moments(f.rel_height);
    out.add("z_mean", m.mean);
    out.add("z_sd", m.sd);
    out.add("z_moment2", m.m2);
    out.add("z_moment3", m.m3);
    out.add("z_moment4", m.m4);
    out.add("z_skewness", m.skewness);
    out.add("z_kurtosis", m.kurtosis);
}

// ---------------------------------------------------------------- radial
void describe_radial(Catalogue& c) {
    for (int k = 0; k < kProfileLayers; ++k) {
        const std::string span = "layer " + std::to_string(k + 1) + " of " + std::to_string(kProfileLayers) + " (h in [" +
                                 std::to_string(k) + "/15, " + std::to_string(k + 1) + "/15))";
        c.add(indexed("profile_r50", k), "1", "median r / H in " + span + "; 0 when empty");
        c.add(indexed("profile_r90", k), "1", "90 % quantile of r / H in " + span);
        c.add(indexed("profile_shape", k), "1", "90 % quantile of r / R in " + span + " (crown outline, size-free)");
    }
    for (int k = 0; k < kRadialBins; ++k)
        c.add(indexed("rhist", k), "1",
              "fraction of voxel points with r / R in [" + std::to_string(k) + ", " + std::to_string(k + 1) + ") / 10 (last bin open)");
    c.add("r_mean", "1", "mean of r / R");
    c.add("r_sd", "1", "standard deviation of r / R");
    c.add("r_skewness", "1", "skewness of r / R");
    c.add("r_kurtosis", "1", "kurtosis of r / R");
}

void compute_radial(const TreeFrame& f, FeatureSink& out) {
    std::vector<std::vector<float>> per_layer(kProfileLayers);
    for (std::size_t i = 0; i < f.points.size(); ++i)
        per_layer[std::min(kProfileLayers - 1, static_cast<int>(f.rel_height[i] * kProfileLayers))].push_back(f.radius[i]);
    for (int k = 0; k < kProfileLayers; ++k) {
        const auto& r = per_layer[k];
        out.add(indexed("profile_r50", k), quantile(r, 0.5) / f.height);
        out.add(indexed("profile_r90", k), quantile(r, 0.9) / f.height);
        out.add(indexed("profile_shape", k), quantile(r, 0.9) / f.crown_radius);
    }
    std::vector<double> hist(kRadialBins, 0.0);
    std::vector<float> relative;
    for (float r : f.radius) {
        const float q = r / f.crown_radius;
        relative.push_back(q);
        hist[std::min(kRadialBins - 1, static_cast<int>(q * kRadialBins))] += 1.0;
    }
    for (int k = 0; k < kRadialBins; ++k) out.add(indexed("rhist", k), hist[k] / static_cast<double>(f.points.size()));
    const Moments m = moments(relative);
    out.add("r_mean", m.mean);
    out.add("r_sd", m.sd);
    out.add("r_skewness", m.skewness);
    out.add("r_kurtosis", m.kurtosis);
}

// ---------------------------------------------------------------- horizontal
void describe_horizontal(Catalogue& c) {
    const char* thirds[] = {"lower", "middle", "upper"};
    for (int t = 0; t < 3; ++t)
        c.add(std::string("horizontal_eigen_ratio_") + thirds[t], "1",
              std::string("smaller / larger eigenvalue of the xy covariance of the ") + thirds[t] + " third of the height");
    for (int t = 0; t < 3; ++t)
        for (int m = 1; m <= 3; ++m)
            c.add(std::string("azimuth_fourier_") + thirds[t] + "_" + std::to_string(m), "1",
                  "|mean of exp(i " + std::to_string(m) + " phi)| over the azimuths phi of the " + thirds[t] +
                          " third's points with r > 0.2 R (crown asymmetry; 0 = round)");
    for (int k = 0; k < kCrownSectors; ++k)
        c.add(indexed("sector_radius_sorted", k + 1), "1",
              "crown outline: 90 % radius / R in each of 8 azimuth sectors (45 deg, from the major axis) of the crown, sorted "
              "from the largest; this is rank " +
                      std::to_string(k + 1));
    c.add("sector_radius_cv", "1", "coefficient of variation of the 8 sector radii");
    c.add("major_minor_sd_ratio", "1", "sqrt(var y / var x) of the voxel points (principal axes)");
    c.add("crown_eccentricity", "1", "sqrt(1 - var y / var x)");
}

void compute_horizontal(const TreeFrame& f, FeatureSink& out) {
    const char* thirds[] = {"lower", "middle", "upper"};
    std::vector<std::vector<std::size_t>> parts;
    for (int t = 0; t < 3; ++t) parts.push_back(layer(f, t / 3.0, (t + 1) / 3.0));
    for (int t = 0; t < 3; ++t) {
        Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        for (auto i : parts[t]) mean += f.points[i].head<2>().cast<double>();
        double ratio = 0;
        if (parts[t].size() >= 3) {
            mean /= static_cast<double>(parts[t].size());
            for (auto i : parts[t]) {
                const Eigen::Vector2d d = f.points[i].head<2>().cast<double>() - mean;
                cov += d * d.transpose();
            }
            const Eigen::Vector2d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvalues();
            ratio = ev(1) > 0 ? ev(0) / ev(1) : 0.0;
        }
        out.add(std::string("horizontal_eigen_ratio_") + thirds[t], ratio);
    }
    for (int t = 0; t < 3; ++t) {
        std::complex<double> sum[3];
        int n = 0;
        for (auto i : parts[t]) {
            if (f.radius[i] <= 0.2f * f.crown_radius) continue;
            const double phi = std::atan2(f.points[i].y(), f.points[i].x());
            for (int m = 0; m < 3; ++m) sum[m] += std::polar(1.0, (m + 1) * phi);
            ++n;
        }
        for (int m = 1; m <= 3; ++m)
            out.add(std::string("azimuth_fourier_") + thirds[t] + "_" + std::to_string(m), n > 0 ? std::abs(sum[m - 1]) / n : 0.0);
    }
    std::vector<std::vector<float>> sectors(kCrownSectors);
    for (std::size_t i = 0; i < f.points.size(); ++i) {
        if (f.points[i].z() < f.crown_base) continue;
        const double phi = std::atan2(f.points[i].y(), f.points[i].x()) + std::numbers::pi;  // [0, 2 pi]
        sectors[std::min(kCrownSectors - 1, static_cast<int>(phi / (2 * std::numbers::pi) * kCrownSectors))].push_back(f.radius[i]);
    }
    std::vector<float> sector_radius;
    for (auto& s : sectors) sector_radius.push_back(quantile(s, 0.9) / f.crown_radius);
    std::sort(sector_radius.begin(), sector_radius.end(), std::greater<>());
    for (int k = 0; k < kCrownSectors; ++k) out.add(indexed("sector_radius_sorted", k + 1), sector_radius[k]);
    const Moments m = moments(sector_radius);
    out.add("sector_radius_cv", m.mean > 0 ? m.sd / m.mean : 0.0);
    const double ratio = f.major_variance > 0 ? f.minor_variance / f.major_variance : 0.0;
    out.add("major_minor_sd_ratio", std::sqrt(std::max(0.0, ratio)));
    out.add("crown_eccentricity", std::sqrt(std::max(0.0, 1.0 - ratio)));
}

// ---------------------------------------------------------------- structure
namespace {

struct CellKey {
    long x, y, z;
    bool operator==(const CellKey&) const = default;
};
struct CellHash {
    std::size_t operator()(const CellKey& k) const { return static_cast<std::size_t>(k.x * 73856093L ^ k.y * 19349663L ^ k.z * 83492791L); }
};

// Occupied cells of size `cell` (grid anchored at the points' minimum corner in the frame) and
// how many points each holds.
std::unordered_map<CellKey, int, CellHash> occupancy(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& lo, float cell) {
    std::unordered_map<CellKey, int, CellHash> cells;
    for (const auto& p : pts) {
        const Eigen::Vector3f q = (p - lo) / cell;
        ++cells[{static_cast<long>(q.x()), static_cast<long>(q.y()), static_cast<long>(q.z())}];
    }
    return cells;
}

Eigen::Vector3f min_corner(const std::vector<Eigen::Vector3f>& pts) {
    Eigen::Vector3f lo = pts.front();
    for (const auto& p : pts) lo = lo.cwiseMin(p);
    return lo;
}

// Convex hull of 2-D points (Andrew's monotone chain), counter-clockwise.
std::vector<Eigen::Vector2f> hull_2d(std::vector<Eigen::Vector2f> pts) {
    std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
    if (pts.size() < 3) return pts;
    auto cross = [](const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
        return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
    };
    std::vector<Eigen::Vector2f> h(2 * pts.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
        h[k++] = pts[i];
    }
    for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
        while (k >= t && cross(h[k - 2], h[k - 1], pts[i - 1]) <= 0) --k;
        h[k++] = pts[i - 1];
    }
    h.resize(k - 1);
    return h;
}

bool inside(const std::vector<Eigen::Vector2f>& hull, const Eigen::Vector2f& p) {
    for (std::size_t i = 0; i < hull.size(); ++i) {
        const auto& a = hull[i];
        const auto& b = hull[(i + 1) % hull.size()];
        if ((b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x()) < 0) return false;
    }
    return true;
}

double polygon_area(const std::vector<Eigen::Vector2f>& poly) {
    double a = 0;
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const auto& p = poly[i];
        const auto& q = poly[(i + 1) % poly.size()];
        a += double(p.x()) * q.y() - double(q.x()) * p.y();
    }
    return std::abs(a) / 2;
}

}  // namespace

void describe_structure(Catalogue& c) {
    for (int n : {10, 20, 40})
        c.add("occupancy_" + std::to_string(n), "1",
              "occupied fraction of the cells (size H/" + std::to_string(n) + ") of the box spanned by the occupied cells");
    for (int n : {10, 20})
        c.add("count_cv_" + std::to_string(n), "1",
              "inhomogeneity: coefficient of variation of raw points per occupied cell (size H/" + std::to_string(n) + ")");
    c.add("count_gini_20", "1", "inhomogeneity: Gini coefficient of raw points per occupied cell (size H/20)");
    for (int n : {10, 20})
        c.add("lacunarity_" + std::to_string(n), "1",
              "E[M^2] / E[M]^2 of voxel points M per cell (size H/" + std::to_string(n) + ") over all cells of the box");
    for (int k = 1; k <= 5; ++k)
        c.add(indexed("boxcount_step", k), "1",
              "log2 of occupied boxes at size H/2^" + std::to_string(k + 1) + " over those at H/2^" + std::to_string(k));
    c.add("boxcount_dimension", "1", "box-counting dimension: slope of log2 N(s) against log2(H/s) for s = H/4 .. H/64");
    c.add("boxcount_r2", "1", "coefficient of determination of that fit");
    c.add("projection_gap_fraction", "1", "empty fraction of the H/40 ground-plan cells inside the convex hull of the projected crown");
    c.add("projection_hull_ratio", "1", "area of the convex hull of the projected points / (pi R^2)");
    c.add("vertical_gap_fraction", "1", "fraction of 50 height layers holding fewer than 0.2 % of the voxel points");
}

void compute_structure(const TreeFrame& f, FeatureSink& out) {
    const Eigen::Vector3f lo = min_corner(f.points);
    for (int n : {10, 20, 40}) {
        const auto cells = occupancy(f.points, lo, f.height / n);
        Eigen::Array3f hi = Eigen::Array3f::Zero();
        for (const auto& [k, count] : cells) hi = hi.max(Eigen::Array3f(k.x, k.y, k.z));
        out.add("occupancy_" + std::to_string(n), cells.size() / static_cast<double>((hi + 1).prod()));
    }
    for (int n : {10, 20}) {
        std::vector<float> counts;
        for (const auto& [k, count] : occupancy(f.raw, min_corner(f.raw), f.height / n)) counts.push_back(static_cast<float>(count));
        const Moments m = moments(counts);
        out.add("count_cv_" + std::to_string(n), m.mean > 0 ? m.sd / m.mean : 0.0);
    }
    {
        std::vector<float> counts;
        for (const auto& [k, count] : occupancy(f.raw, min_corner(f.raw), f.height / 20)) counts.push_back(static_cast<float>(count));
        std::sort(counts.begin(), counts.end());
        double weighted = 0, total = 0;
        for (std::size_t i = 0; i < counts.size(); ++i) weighted += (i + 1.0) * counts[i], total += counts[i];
        const double n = static_cast<double>(counts.size());
        out.add("count_gini_20", total > 0 ? (2 * weighted) / (n * total) - (n + 1) / n : 0.0);
    }
    for (int n : {10, 20}) {
        const auto cells = occupancy(f.points, lo, f.height / n);
        Eigen::Array3f hi = Eigen::Array3f::Zero();
        double s1 = 0, s2 = 0;
        for (const auto& [k, count] : cells) {
            hi = hi.max(Eigen::Array3f(k.x, k.y, k.z));
            s1 += count, s2 += double(count) * count;
        }
        const double boxes = (hi + 1).prod();
        out.add("lacunarity_" + std::to_string(n), s1 > 0 ? (s2 / boxes) / ((s1 / boxes) * (s1 / boxes)) : 0.0);
    }
    std::vector<double> log_count;
    for (int k = 1; k <= 6; ++k)
        log_count.push_back(std::log2(static_cast<double>(occupancy(f.points, lo, f.height / std::pow(2.0f, k)).size())));
    for (int k = 1; k <= 5; ++k) out.add(indexed("boxcount_step", k), log_count[k] - log_count[k - 1]);
    {
        // Least squares of log2 N against k = 2..6 (sizes H/4 .. H/64).
        double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
        const int n = 5;
        for (int k = 2; k <= 6; ++k) {
            const double y = log_count[k - 1];
            sx += k, sy += y, sxx += k * k, sxy += k * y, syy += y * y;
        }
        const double vx = sxx - sx * sx / n, vy = syy - sy * sy / n, cxy = sxy - sx * sy / n;
        out.add("boxcount_dimension", vx > 0 ? cxy / vx : 0.0);
        out.add("boxcount_r2", vx > 0 && vy > 0 ? cxy * cxy / (vx * vy) : 0.0);
    }
    {
        std::vector<Eigen::Vector2f> plan;
        for (const auto& p : f.points) plan.push_back(p.head<2>());
        const auto hull = hull_2d(plan);
        const float cell = f.height / 40;
        const Eigen::Vector2f lo2 = lo.head<2>();
        std::unordered_map<CellKey, int, CellHash> filled;
        for (const auto& p : plan) {
            const Eigen::Vector2f q = (p - lo2) / cell;
            filled[{static_cast<long>(q.x()), static_cast<long>(q.y()), 0}] = 1;
        }
        long in_hull = 0, occupied = 0;
        Eigen::Vector2f hi2 = lo2;
        for (const auto& p : plan) hi2 = hi2.cwiseMax(p);
        const long nx = static_cast<long>((hi2.x() - lo2.x()) / cell) + 1, ny = static_cast<long>((hi2.y() - lo2.y()) / cell) + 1;
        for (long ix = 0; ix < nx; ++ix)
            for (long iy = 0; iy < ny; ++iy) {
                const Eigen::Vector2f centre = lo2 + cell * Eigen::Vector2f(ix + 0.5f, iy + 0.5f);
                if (hull.size() < 3 || !inside(hull, centre)) continue;
                ++in_hull;
                occupied += filled.count({ix, iy, 0});
            }
        out.add("projection_gap_fraction", in_hull > 0 ? 1.0 - static_cast<double>(occupied) / in_hull : 0.0);
        out.add("projection_hull_ratio",
                hull.size() >= 3 ? polygon_area(hull) / (std::numbers::pi * f.crown_radius * f.crown_radius) : 0.0);
    }
    std::vector<int> layers(kCrownBaseLayers, 0);
    for (float h : f.rel_height) ++layers[std::min(kCrownBaseLayers - 1, static_cast<int>(h * kCrownBaseLayers))];
    const double sparse = 0.002 * static_cast<double>(f.points.size());
    out.add("vertical_gap_fraction",
            std::count_if(layers.begin(), layers.end(), [&](int n) { return n < sparse; }) / static_cast<double>(kCrownBaseLayers));
}

}  // namespace treelobes::classify::detail
