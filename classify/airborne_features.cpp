// Airborne group: what an airborne laser scanner sees of a crown at a few points per m^2: the
// height above the lowest ground return and the crown's width, the share of points per height layer (density profile),
// intensity (normalised within the clip: against the ground returns of the same clip, which share
// the flight, the range and the gain, and against the crown's own median), returns (single, first
// and last returns per height layer: how far the pulses get into the crown), the crown-top
// surface on a 1 m raster (the canopy height model of the crown: dome or flat top, roughness)
// and, when the points carry colours, the chromaticity. Computed from as few points as the crown
// has (a crown of 6 points still has a height, a width and an intensity); a value that cannot be
// computed (no intensity, no returns, no ground returns, no colour, an empty layer) is missing
// (NaN), which JointBoost and XGBoost both handle (docs/classify.md). Every value is a ratio,
// share or height in the crown's own frame (centroid, principal axes), so it does not change
// with position or heading and changes little with the point density.
#include "classify/feature_groups.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

namespace treelobes::classify::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kDensityLayers = 5;  // density profile layers
constexpr double kTopCell = 1.0;   // crown-top raster cell, m (ALS: a few points per m^2)

// Missing values stay NaN here (the other groups map an undefined ratio to 0).
void emit(FeatureSink& out, const std::string& name, double value) {
    if (std::isfinite(value))
        out.add(name, value);
    else
        out.missing(name);
}

double median(std::vector<float> v) { return v.empty() ? kNaN : quantile(std::move(v), 0.5); }

double ratio(double a, double b) { return (std::isfinite(a) && std::isfinite(b) && b > 0) ? a / b : kNaN; }

// Share of `count` in `total`, missing when total is 0.
double share(std::size_t count, std::size_t total) { return total ? static_cast<double>(count) / static_cast<double>(total) : kNaN; }

struct CrownPoints {
    std::vector<Eigen::Vector2f> xy;  // horizontal position in the crown frame (centroid, principal axes)
    std::vector<float> h;             // height above the ground level
    float top = 0, radius = 0;
};

CrownPoints crown_frame(const AirborneInput& in) {
    const PointCloud& c = *in.crown;
    CrownPoints p;
    float ground = std::numeric_limits<float>::max();
    if (in.ground_z)
        ground = *in.ground_z;
    else
        for (const auto& q : c.positions) ground = std::min(ground, q.z());
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const auto& q : c.positions) centre += q.head<2>().cast<double>();
    centre /= static_cast<double>(c.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const auto& q : c.positions) {
        const Eigen::Vector2d d = q.head<2>().cast<double>() - centre;
        cov += d * d.transpose();
    }
    const Eigen::Matrix2d axes = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvectors();
    std::vector<float> r;
    for (const auto& q : c.positions) {
        const Eigen::Vector2d d = q.head<2>().cast<double>() - centre;
        p.xy.emplace_back(static_cast<float>(d.dot(axes.col(1))), static_cast<float>(d.dot(axes.col(0))));
        p.h.push_back(std::max(0.0f, q.z() - ground));
        r.push_back(static_cast<float>(d.norm()));
        p.top = std::max(p.top, p.h.back());
    }
    p.radius = quantile(r, 0.9);
    return p;
}

// Area of the convex hull of the points (Andrew's monotone chain); 0 below 3 points.
double hull_area(std::vector<Eigen::Vector2f> pts) {
    if (pts.size() < 3) return 0.0;
    std::sort(pts.begin(), pts.end(),
              [](const Eigen::Vector2f& a, const Eigen::Vector2f& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
    const auto cross = [](const Eigen::Vector2f& o, const Eigen::Vector2f& a, const Eigen::Vector2f& b) {
        return double(a.x() - o.x()) * (b.y() - o.y()) - double(a.y() - o.y()) * (b.x() - o.x());
    };
    std::vector<Eigen::Vector2f> hull(2 * pts.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
        hull[k++] = pts[i];
    }
    for (std::size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
        hull[k++] = pts[i];
    }
    double area = 0;
    for (std::size_t i = 0; i + 1 < k; ++i) area += double(hull[i].x()) * hull[i + 1].y() - double(hull[i + 1].x()) * hull[i].y();
    return std::abs(area) / 2;
}

void add_shape(const CrownPoints& p, FeatureSink& out) {
    emit(out, "als_height", p.top);
    emit(out, "als_crown_radius", p.radius);
    emit(out, "als_radius_height_ratio", ratio(p.radius, p.top));
    emit(out, "als_crown_depth_ratio", ratio(p.top - quantile(p.h, 0.1), p.top));
    std::vector<std::size_t> layer(kDensityLayers, 0);
    for (float h : p.h)
        ++layer[std::min(kDensityLayers - 1, static_cast<int>(p.top > 0 ? kDensityLayers * h / p.top : kDensityLayers - 1))];
    for (int k = 0; k < kDensityLayers; ++k) emit(out, indexed("als_layer_share", k), share(layer[k], p.h.size()));
    const Moments m = moments(p.h);
    emit(out, "als_height_cv", ratio(m.sd, m.mean));
    emit(out, "als_height_q25", quantile(p.h, 0.25));
    emit(out, "als_height_q50", quantile(p.h, 0.5));
    emit(out, "als_height_q75", quantile(p.h, 0.75));
    emit(out, "als_crown_area", hull_area(p.xy));
}

void add_intensity(const AirborneInput& in, const CrownPoints& p, FeatureSink& out) {
    const PointCloud& c = *in.crown;
    bool any = false;
    for (auto v : c.intensity) any = any || v > 0;
    if (!any) {
        for (const char* name : {"als_intensity_ground_ratio", "als_intensity_cv", "als_intensity_top_ratio", "als_intensity_q10_ratio",
                                 "als_intensity_q90_ratio", "als_intensity_single_ratio", "als_intensity_upper_first_ground_ratio",
                                 "als_intensity_lower_ratio"})
            emit(out, name, kNaN);
        return;
    }
    std::vector<float> all, top, single, upper_first, lower;
    const bool returns = c.number_of_returns.size() == c.size();
    const bool first = c.return_number.size() == c.size();
    for (std::size_t i = 0; i < c.size(); ++i) {
        all.push_back(c.intensity[i]);
        if (p.h[i] >= 0.8f * p.top) top.push_back(c.intensity[i]);
        if (p.h[i] < p.top / 3) lower.push_back(c.intensity[i]);
        if (first && c.return_number[i] == 1 && p.h[i] >= 2 * p.top / 3) upper_first.push_back(c.intensity[i]);
        if (returns && c.number_of_returns[i] == 1) single.push_back(c.intensity[i]);
    }
    const double crown = median(all);
    const Moments m = moments(all);
    emit(out, "als_intensity_ground_ratio", ratio(crown, in.ground_intensity));
    emit(out, "als_intensity_cv", ratio(m.sd, m.mean));
    emit(out, "als_intensity_top_ratio", ratio(median(top), crown));
    emit(out, "als_intensity_q10_ratio", ratio(quantile(all, 0.1), crown));
    emit(out, "als_intensity_q90_ratio", ratio(quantile(all, 0.9), crown));
    emit(out, "als_intensity_single_ratio", ratio(median(single), crown));
    emit(out, "als_intensity_upper_first_ground_ratio", ratio(median(upper_first), in.ground_intensity));
    emit(out, "als_intensity_lower_ratio", ratio(median(lower), crown));
}

void add_returns(const AirborneInput& in, const CrownPoints& p, FeatureSink& out) {
    const PointCloud& c = *in.crown;
    const bool returns = c.return_number.size() == c.size() && c.number_of_returns.size() == c.size();
    std::size_t single = 0, first = 0, second = 0, later = 0, sum = 0;
    std::size_t last[3] = {0, 0, 0}, in_layer[3] = {0, 0, 0};
    if (returns)
        for (std::size_t i = 0; i < c.size(); ++i) {
            const int n = c.number_of_returns[i], r = c.return_number[i];
            single += n == 1, first += r == 1, second += r == 2, later += r >= 3, sum += static_cast<std::size_t>(n);
            const int layer = std::min(2, static_cast<int>(p.top > 0 ? 3 * p.h[i] / p.top : 2));
            ++in_layer[layer];
            last[layer] += r == n;
        }
    const std::size_t total = returns ? c.size() : 0;
    emit(out, "als_single_share", share(single, total));
    emit(out, "als_first_share", share(first, total));
    emit(out, "als_second_share", share(second, total));
    emit(out, "als_third_plus_share", share(later, total));
    emit(out, "als_last_share_lower", returns ? share(last[0], in_layer[0]) : kNaN);
    emit(out, "als_last_share_middle", returns ? share(last[1], in_layer[1]) : kNaN);
    emit(out, "als_last_share_upper", returns ? share(last[2], in_layer[2]) : kNaN);
    emit(out, "als_mean_returns", total ? static_cast<double>(sum) / static_cast<double>(total) : kNaN);
    emit(out, "als_ground_share",
         in.ground_returns + c.size() > 0 && in.ground_z ? share(in.ground_returns, in.ground_returns + c.size()) : kNaN);
}

// The crown top on a 1 m raster in the crown frame: per cell the highest point. A dome (pines,
// many broadleaves) drops from the apex outwards; a flat or ragged top does not.
void add_top(const CrownPoints& p, FeatureSink& out) {
    std::map<std::pair<int, int>, float> cells;
    for (std::size_t i = 0; i < p.h.size(); ++i) {
        const std::pair<int, int> key{static_cast<int>(std::floor(p.xy[i].x() / kTopCell)),
                                      static_cast<int>(std::floor(p.xy[i].y() / kTopCell))};
        auto [it, inserted] = cells.emplace(key, p.h[i]);
        if (!inserted) it->second = std::max(it->second, p.h[i]);
    }
    double drop = 0;
    std::size_t flat = 0;
    // Least squares of top = c - a r^2 over the cells (r: cell centre to the crown centre).
    double s1 = 0, sr = 0, srr = 0, sz = 0, srz = 0;
    for (const auto& [key, top] : cells) {
        drop += (p.top - top) / std::max(p.top, 1e-6f);
        flat += top >= 0.9f * p.top;
        const double x = (key.first + 0.5) * kTopCell, y = (key.second + 0.5) * kTopCell, r2 = x * x + y * y;
        s1 += 1, sr += r2, srr += r2 * r2, sz += top, srz += r2 * top;
    }
    emit(out, "als_top_drop_mean", p.top > 0 ? drop / s1 : kNaN);
    emit(out, "als_top_flat_share", share(flat, cells.size()));
    const double det = s1 * srr - sr * sr;
    double curvature = kNaN, roughness = kNaN;
    if (cells.size() >= 3 && det > 1e-9 && p.top > 0 && p.radius > 0) {
        const double slope = (s1 * srz - sr * sz) / det, intercept = (sz - slope * sr) / s1;
        curvature = -slope * p.radius * p.radius / p.top;
        double rss = 0;
        for (const auto& [key, top] : cells) {
            const double x = (key.first + 0.5) * kTopCell, y = (key.second + 0.5) * kTopCell;
            const double e = top - (intercept + slope * (x * x + y * y));
            rss += e * e;
        }
        roughness = std::sqrt(rss / s1) / p.top;
    }
    emit(out, "als_top_curvature", curvature);
    emit(out, "als_top_roughness", roughness);
    const auto apex = std::max_element(p.h.begin(), p.h.end()) - p.h.begin();
    emit(out, "als_apex_offset", p.radius > 0 ? p.xy[apex].norm() / p.radius : kNaN);
}

void add_colour(const AirborneInput& in, const CrownPoints& p, FeatureSink& out) {
    const PointCloud& c = *in.crown;
    std::vector<float> red, green, brightness;
    if (c.rgb.size() == c.size())
        for (std::size_t i = 0; i < c.size(); ++i) {
            if (p.h[i] < 0.5f * p.top) continue;  // the sunlit upper crown, as the camera sees it
            const double sum = double(c.rgb[i][0]) + c.rgb[i][1] + c.rgb[i][2];
            if (sum <= 0) continue;
            red.push_back(static_cast<float>(c.rgb[i][0] / sum));
            green.push_back(static_cast<float>(c.rgb[i][1] / sum));
            brightness.push_back(static_cast<float>(sum));
        }
    const Moments b = moments(brightness);
    emit(out, "als_rgb_red_chroma", red.empty() ? kNaN : moments(red).mean);
    emit(out, "als_rgb_green_chroma", green.empty() ? kNaN : moments(green).mean);
    emit(out, "als_rgb_brightness_cv", brightness.empty() ? kNaN : ratio(b.sd, b.mean));
}

}  // namespace

void describe_airborne(Catalogue& c) {
    c.add("als_height", "m",
          "height of the highest crown point above the lowest ground return (without ground returns: above the lowest crown point)");
    c.add("als_crown_radius", "m", "90 % quantile of the crown points' horizontal distances to their centroid");
    c.add("als_radius_height_ratio", "1", "als_crown_radius / als_height");
    c.add("als_crown_depth_ratio", "1", "(als_height - 10 % height quantile of the crown points) / als_height");
    for (int k = 0; k < kDensityLayers; ++k)
        c.add(indexed("als_layer_share", k), "1",
              "density profile: share of the crown points with height / als_height in [" + std::to_string(k * 20) + ", " +
                      std::to_string((k + 1) * 20) + ") %");
    c.add("als_height_cv", "1", "coefficient of variation of the crown points' heights above ground");
    c.add("als_height_q25", "m", "25 % quantile of the crown points' heights above ground");
    c.add("als_height_q50", "m", "median height of the crown points above ground");
    c.add("als_height_q75", "m", "75 % quantile of the crown points' heights above ground");
    c.add("als_crown_area", "m^2", "area of the convex hull of the crown points seen from above (0 below 3 points)");
    c.add("als_intensity_ground_ratio", "1",
          "median intensity of the crown points / median intensity of the clip's ground returns (same flight, range and gain: "
          "the per-file normalisation); missing without intensity or ground returns");
    c.add("als_intensity_cv", "1", "coefficient of variation of the crown points' intensities; missing without intensity");
    c.add("als_intensity_top_ratio", "1", "median intensity of the points above 80 % of als_height / median of the crown");
    c.add("als_intensity_q10_ratio", "1", "10 % intensity quantile / median intensity of the crown");
    c.add("als_intensity_q90_ratio", "1", "90 % intensity quantile / median intensity of the crown");
    c.add("als_intensity_single_ratio", "1", "median intensity of single returns / median intensity of the crown; missing without returns");
    c.add("als_intensity_upper_first_ground_ratio", "1",
          "median intensity of the first returns above 2/3 of als_height (the sunlit top) / median intensity of the ground returns");
    c.add("als_intensity_lower_ratio", "1",
          "median intensity of the points below 1/3 of als_height / median of the crown; missing when none");
    c.add("als_single_share", "1", "share of the crown points that are single returns (number of returns 1); missing without returns");
    c.add("als_first_share", "1", "share of the crown points that are first returns");
    c.add("als_second_share", "1", "share of the crown points that are second returns");
    c.add("als_third_plus_share", "1", "share of the crown points that are third or later returns");
    c.add("als_last_share_lower", "1", "penetration: share of last returns among the crown points below 1/3 of als_height");
    c.add("als_last_share_middle", "1", "share of last returns among the crown points between 1/3 and 2/3 of als_height");
    c.add("als_last_share_upper", "1", "share of last returns among the crown points above 2/3 of als_height");
    c.add("als_mean_returns", "1", "mean number of returns of the pulses that gave the crown points");
    c.add("als_ground_share", "1",
          "ground returns of the clip / (ground returns + crown points): how many pulses got through the crown; missing without ground "
          "returns");
    c.add("als_top_drop_mean", "1",
          "crown top on a 1 m raster (crown frame, highest point per cell): mean of (als_height - cell top) / als_height");
    c.add("als_top_flat_share", "1", "share of the raster cells whose top is above 90 % of als_height");
    c.add("als_top_curvature", "1",
          "a R^2 / H of the least-squares fit top = c - a r^2 over the cells (dome > 0, flat 0); missing below 3 cells");
    c.add("als_top_roughness", "1", "RMS residual of that fit / als_height");
    c.add("als_apex_offset", "1", "horizontal distance of the highest point to the crown centroid / als_crown_radius");
    c.add("als_rgb_red_chroma", "1", "mean R / (R + G + B) of the points above half the height; missing without colours");
    c.add("als_rgb_green_chroma", "1", "mean G / (R + G + B) of the points above half the height");
    c.add("als_rgb_brightness_cv", "1", "coefficient of variation of R + G + B of the points above half the height");
}

void compute_airborne(const AirborneInput& in, FeatureSink& out) {
    const CrownPoints p = crown_frame(in);
    add_shape(p, out);
    add_intensity(in, p, out);
    add_returns(in, p, out);
    add_top(p, out);
    add_colour(in, p, out);
}

float airborne_crown_radius(const AirborneInput& in) { return crown_frame(in).radius; }

}  // namespace treelobes::classify::detail
