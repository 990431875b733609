// Feature extraction: builds the tree frame (cleaning, voxel reduction, stem foot, principal
// axes) and runs the feature groups in catalogue order.
#include "classify/features.hpp"

#include "classify/crown.hpp"
#include "classify/feature_groups.hpp"
#include "core/error.hpp"
#include "reconstruct/preprocess.hpp"
#include "reconstruct/skeleton.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>

namespace treelobes::classify {

namespace detail {

FeatureSink::FeatureSink(std::vector<double>& values) : values_(values) {}

void FeatureSink::add(const std::string& name, double value) {
    const auto& catalogue = feature_catalogue();
    const std::size_t index = values_.size();
    if (index >= catalogue.size() || catalogue[index].name != name)
        throw Error(ExitCode::Internal, "feature '" + name + "' emitted at position " + std::to_string(index) +
                                                ", the catalogue expects '" +
                                                (index < catalogue.size() ? catalogue[index].name : std::string("nothing")) + "'");
    // A degenerate tree can make a ratio undefined; 0 keeps the vector usable and is rare.
    values_.push_back(std::isfinite(value) ? value : 0.0);
}

void FeatureSink::missing(const std::string& name) {
    add(name, 0.0);
    values_.back() = std::numeric_limits<double>::quiet_NaN();
}

float quantile(std::vector<float> values, double q) {
    if (values.empty()) return 0.0f;
    const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(values.size() - 1)));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
}

Moments moments(const std::vector<float>& values) {
    Moments m;
    if (values.empty()) return m;
    const double n = static_cast<double>(values.size());
    for (float v : values) m.mean += v;
    m.mean /= n;
    for (float v : values) {
        const double d = v - m.mean;
        m.m2 += d * d, m.m3 += d * d * d, m.m4 += d * d * d * d;
    }
    m.m2 /= n, m.m3 /= n, m.m4 /= n;
    m.sd = std::sqrt(m.m2);
    if (m.m2 > 1e-12) {
        m.skewness = m.m3 / std::pow(m.m2, 1.5);
        m.kurtosis = m.m4 / (m.m2 * m.m2);
    }
    return m;
}

std::string indexed(const std::string& prefix, int index) {
    char buffer[16];
    std::snprintf(buffer, sizeof(buffer), "%02d", index);
    return prefix + "_" + buffer;
}

}  // namespace detail

namespace {

using detail::TreeFrame;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::vector<FeatureInfo> build_catalogue() {
    std::vector<FeatureInfo> list;
    const std::pair<const char*, void (*)(detail::Catalogue&)> groups[] = {
            {"shape", detail::describe_shape},         {"vertical", detail::describe_vertical},
            {"radial", detail::describe_radial},       {"horizontal", detail::describe_horizontal},
            {"structure", detail::describe_structure}, {"normals", detail::describe_normals},
            {"hull", detail::describe_hull},           {"skeleton", detail::describe_skeleton},
            {"envelope", detail::describe_envelope},   {"scan", detail::describe_scan},
            {"airborne", detail::describe_airborne},
    };
    for (const auto& [group, describe] : groups) {
        detail::Catalogue catalogue(list, group);
        describe(catalogue);
    }
    return list;
}

// Evenly thinned copy (every k-th point) so very large scans cost a bounded time.
std::vector<Eigen::Vector3f> thinned(const std::vector<Eigen::Vector3f>& points, std::size_t max_points) {
    if (points.size() <= max_points || max_points == 0) return points;
    std::vector<Eigen::Vector3f> out;
    const double step = static_cast<double>(points.size()) / static_cast<double>(max_points);
    for (std::size_t i = 0; i < max_points; ++i) out.push_back(points[static_cast<std::size_t>(i * step)]);
    return out;
}

std::vector<float> coordinate(const std::vector<Eigen::Vector3f>& points, int axis) {
    std::vector<float> out;
    out.reserve(points.size());
    for (const auto& p : points) out.push_back(p[axis]);
    return out;
}

// Geometric median of the points' horizontal positions (Weiszfeld iterations on at most 20,000
// evenly spaced points). Unlike the median of x and of y it turns with the points, so the frame
// (and every feature) does not depend on the heading of the tree.
Eigen::Vector2f geometric_median(const std::vector<Eigen::Vector3f>& points) {
    const auto sample = thinned(points, 20000);
    Eigen::Vector2d m = Eigen::Vector2d::Zero();
    for (const auto& p : sample) m += p.head<2>().cast<double>();
    m /= static_cast<double>(sample.size());
    for (int iteration = 0; iteration < 100; ++iteration) {
        Eigen::Vector2d sum = Eigen::Vector2d::Zero();
        double weight = 0;
        for (const auto& p : sample) {
            const Eigen::Vector2d q = p.head<2>().cast<double>();
            const double w = 1.0 / std::max((q - m).norm(), 1e-6);
            sum += w * q, weight += w;
        }
        const Eigen::Vector2d next = sum / weight;
        const double step = (next - m).norm();
        m = next;
        if (step < 1e-6) break;
    }
    return m.cast<float>();
}

// The stem axis: the geometric median of the layer 1-5 % of the height above the lowest points
// (above a flat ground, below the crown) when that layer is a narrow stem; otherwise (airborne
// scans, shrubs, sloping ground) the geometric median of the whole tree.
Eigen::Vector2f stem_axis(const std::vector<Eigen::Vector3f>& points, float base, float height) {
    std::vector<Eigen::Vector3f> low;
    for (const auto& p : points)
        if (p.z() - base >= 0.01f * height && p.z() - base < 0.05f * height) low.push_back(p);
    if (low.size() >= 10) {
        const Eigen::Vector2f axis = geometric_median(low);
        std::vector<float> spread;
        for (const auto& p : low) spread.push_back((p.head<2>() - axis).norm());
        if (detail::quantile(spread, 0.9) < 0.15f * height) return axis;
    }
    return geometric_median(points);
}

// Unit vector along the larger-variance horizontal axis, its sign chosen so that the points'
// third moment along it is positive: the frame then depends on the tree only, not on how it
// was turned or mirrored.
Eigen::Vector2f principal_axis(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector2f& centre) {
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const auto& p : points) {
        const Eigen::Vector2d d = (p.head<2>() - centre).cast<double>();
        cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
    Eigen::Vector2d major = eig.eigenvectors().col(1);
    double third = 0;
    for (const auto& p : points) {
        const double t = (p.head<2>() - centre).cast<double>().dot(major);
        third += t * t * t;  // not std::pow: it costs a libm call per point
    }
    if (third < 0) major = -major;
    return major.cast<float>();
}

// The frame of the shape groups; `ground_z` (the lowest ground return of the clip) is the ground
// level when known, else the ground plane found by the cleaning or the lowest points.
TreeFrame build_frame(const PointCloud& cloud, const FeatureOptions& options, const std::string& name, std::optional<float> ground_z) {
    TreeFrame frame;
    frame.options = &options;
    frame.input_points = cloud.size();
    const auto raw = thinned(cloud.positions, options.max_raw_points);
    const auto z = coordinate(raw, 2);
    const float base = detail::quantile(z, 0.001), rough_height = detail::quantile(z, 0.999) - base;
    if (!(rough_height >= 0.5f))
        throw Error::input(name, "not a tree: the points span only " + std::to_string(rough_height) + " m in height");

    // The frame is fixed on the raw points before voxels are formed, so the voxel grid moves and
    // turns with the tree: the same tree anywhere, at any heading, gives the same voxels.
    const Eigen::Vector2f axis = stem_axis(raw, base, rough_height);
    const Eigen::Vector2f major = principal_axis(raw, axis);
    Eigen::Vector2f minor(-major.y(), major.x());
    double third = 0;
    for (const auto& p : raw) {
        const double t = (p.head<2>() - axis).dot(minor);
        third += t * t * t;
    }
    if (third < 0) minor = -minor;
    PointCloud local;
    local.positions.reserve(raw.size());
    for (const auto& p : raw) {
        const Eigen::Vector2f d = p.head<2>() - axis;
        local.positions.emplace_back(d.dot(major), d.dot(minor), p.z() - base);
    }

    frame.voxel = static_cast<float>(std::clamp(rough_height * options.voxel_fraction, options.min_voxel, options.max_voxel));
    PreprocessOptions clean;
    clean.voxel_size = frame.voxel;
    clean.table_width = std::max(options.normal_neighbours, skeleton_table_width(SkeletonOptions{}));
    if (ground_z) clean.ground = GroundMode::Keep;  // the ground returns are gone already (classify/crown.hpp)
    const Preprocessed pre = preprocess_cloud(local, clean, name);

    // Ground: the plane's height under the stem when the scan has ground, else the lowest points.
    float ground = detail::quantile(coordinate(pre.points, 2), 0.001);
    if (ground_z)
        ground = *ground_z - base;
    else if (pre.ground_found)
        ground = -pre.ground_plane.w() / pre.ground_plane.z();  // n.p + d = 0 at x = y = 0
    const Eigen::Vector3f shift(0, 0, ground);
    for (const auto& p : pre.points) frame.points.push_back(p - shift);
    for (const auto& p : local.positions) frame.raw.push_back(p - shift);
    // The table holds indices and distances, unchanged by the shift; the index holds coordinates.
    frame.neighbours = pre.neighbours;
    frame.index = std::make_shared<const KdTree>(frame.points);
    frame.height = detail::quantile(coordinate(frame.points, 2), 0.999);
    if (!(frame.height >= 0.5f)) throw Error::input(name, "not a tree: less than 0.5 m above the ground");

    double sxx = 0, syy = 0, sx = 0, sy = 0;
    for (const auto& p : frame.points) {
        frame.rel_height.push_back(std::clamp(p.z() / frame.height, 0.0f, 1.0f));
        frame.radius.push_back(p.head<2>().norm());
        sx += p.x(), sy += p.y(), sxx += double(p.x()) * p.x(), syy += double(p.y()) * p.y();
    }
    const double n = static_cast<double>(frame.points.size());
    frame.major_variance = static_cast<float>(sxx / n - (sx / n) * (sx / n));
    frame.minor_variance = static_cast<float>(syy / n - (sy / n) * (sy / n));
    frame.crown_radius = std::max(detail::quantile(frame.radius, 0.95), frame.voxel);
    return frame;
}

// The airborne group's input: the crown and the clip's ground returns (their level and median
// intensity, the reference that normalises the crown's intensity per file).
detail::AirborneInput airborne_input(const PointCloud& clip, const CrownExtraction& extraction) {
    detail::AirborneInput in;
    in.crown = &extraction.crown;
    // Airborne crowns have hundreds to thousands of points; a dense terrestrial scan is thinned
    // evenly for this group (its shares, quantiles and raster tops do not need more points).
    constexpr std::size_t kAirbornePoints = 20000;
    if (extraction.crown.size() > kAirbornePoints) {
        std::vector<std::size_t> every;
        const double step = static_cast<double>(extraction.crown.size()) / kAirbornePoints;
        for (std::size_t i = 0; i < kAirbornePoints; ++i) every.push_back(static_cast<std::size_t>(i * step));
        in.thinned = std::make_shared<const PointCloud>(extraction.crown.subset(every));
        in.crown = in.thinned.get();
    }
    in.ground_z = extraction.ground_z;
    in.ground_returns = extraction.counts.ground;
    if (clip.intensity.size() == clip.size() && clip.classification.size() == clip.size()) {
        std::vector<float> ground;
        for (std::size_t i = 0; i < clip.size(); ++i)
            if (clip.classification[i] == 2) ground.push_back(clip.intensity[i]);
        if (!ground.empty()) in.ground_intensity = detail::quantile(ground, 0.5);
    }
    return in;
}

}  // namespace

const std::vector<FeatureInfo>& feature_catalogue() {
    static const std::vector<FeatureInfo> catalogue = build_catalogue();
    return catalogue;
}

std::vector<std::string> feature_names() {
    std::vector<std::string> names;
    for (const auto& info : feature_catalogue()) names.push_back(info.name);
    return names;
}

std::vector<double> compute_features(const PointCloud& cloud, const FeatureOptions& options, const std::string& name,
                                     FeatureTimings* timings, CrownCounts* crown) {
    FeatureTimings local;
    FeatureTimings& t = timings ? *timings : local;
    auto start = Clock::now();
    if (cloud.empty()) throw Error::input(name, "no points");
    CrownExtraction extraction = extract_crown(cloud, options.crown);
    if (crown) *crown = extraction.counts;
    const PointCloud& points = extraction.crown;
    std::vector<double> values;
    values.reserve(feature_catalogue().size());
    detail::FeatureSink out(values);
    if (points.size() < options.min_shape_points) {
        // Too few points for a frame, normals or a skeleton: those groups are missing, the
        // airborne group (height, width, intensity, returns) and the scan density are not.
        if (crown) crown->shape_features = false;
        t.prepare = seconds_since(start);
        for (const auto& info : feature_catalogue())
            if (info.group != "scan" && info.group != "airborne") out.missing(info.name);
        const detail::AirborneInput airborne = airborne_input(cloud, extraction);
        detail::compute_scan(points.size(), detail::airborne_crown_radius(airborne), out);
        detail::compute_airborne(airborne, out);
        t.points = seconds_since(start) - t.prepare;
        return values;
    }
    TreeFrame frame = build_frame(points, options, name, extraction.ground_z);
    t.prepare = seconds_since(start);
    start = Clock::now();
    detail::compute_shape(frame, out);
    detail::compute_vertical(frame, out);
    detail::compute_radial(frame, out);
    detail::compute_horizontal(frame, out);
    detail::compute_structure(frame, out);
    t.points = seconds_since(start);
    start = Clock::now();
    detail::compute_normals(frame, out);
    t.normals = seconds_since(start);
    start = Clock::now();
    detail::compute_hull(frame, out);
    t.hull = seconds_since(start);
    start = Clock::now();
    if (options.skeleton)
        detail::compute_skeleton(frame, out);
    else
        detail::skip_skeleton(out);
    t.skeleton = seconds_since(start);
    start = Clock::now();
    detail::compute_envelope(frame, out);
    detail::compute_scan(frame.input_points, frame.crown_radius, out);
    detail::compute_airborne(airborne_input(cloud, extraction), out);
    t.points += seconds_since(start);
    if (values.size() != feature_catalogue().size())
        throw Error(ExitCode::Internal, "feature extraction produced " + std::to_string(values.size()) + " of " +
                                                std::to_string(feature_catalogue().size()) + " features");
    return values;
}

std::string features_markdown() {
    std::ostringstream md;
    const auto& catalogue = feature_catalogue();
    md << "# Shape features for species classification\n\n"
       << "Generated from `classify::feature_catalogue()` (classify/features.cpp and the group files); a unit test\n"
       << "fails when this file and the code disagree. Regenerate with `treelobes classify features --list > docs/features.md`.\n\n"
       << catalogue.size() << " features per tree, computed by `treelobes classify features` (Livny et al. 2011, §6.1).\n\n"
       << "## Crown, frame and density\n\n"
       << "- The crown is extracted first (classify/crown.hpp): noise (classes 7, 18) and ground returns (class 2) are removed,\n"
       << "  the lowest ground return is the ground level z = 0, points separated from the rest by a vertical gap of more than\n"
       << "  5 m above the crown (high outliers: birds, clouds) go, and with a known ground level so do points below the first\n"
       << "  vertical gap of max(1.5 m, 0.1 H) under the crown that lies below half the height (understorey).\n"
       << "- Crowns of fewer than 50 points after that get only the airborne group and the scan density; every other\n"
       << "  feature is missing (NaN, written `nan`). The airborne group marks what it cannot compute (no intensity, returns,\n"
       << "  ground returns or colours; an empty layer) as missing too. JointBoost learns per stump whether missing values go\n"
       << "  above or below the threshold; XGBoost treats NaN as missing natively (docs/classify.md).\n"
       << "- The points are cleaned and reduced to one point per voxel (reconstruct/preprocess: duplicates, voxel\n"
       << "  grid, statistical outliers, ground plane). Voxel size v = clamp(0.01 H, 0.03 m, 0.25 m) from a rough\n"
       << "  height H (0.1 % to 99.9 % height quantiles), so a thinned scan fills nearly the same voxels.\n"
       << "- Frame: z = 0 at the ground plane under the stem (or the lowest voxel points), the vertical axis through\n"
       << "  the geometric median of the layer 1-5 % of the height above the lowest points when that layer is a narrow\n"
       << "  stem (else the geometric median of all points), x along the major and y along the minor principal\n"
       << "  horizontal axis of the points, signs chosen by their third moments.\n"
       << "  Every feature is therefore invariant to position and heading.\n"
       << "- H = height (99.9 % quantile of z), h = z / H (relative height), r = horizontal distance to the axis,\n"
       << "  R = crown radius (95 % quantile of r). \"Voxel points\" are the reduced points; \"raw points\" the input.\n"
       << "- Undefined values of the shape groups (empty layer, no visible stem) are 0.\n\n";
    std::string group;
    for (const auto& f : catalogue) {
        if (f.group != group) {
            group = f.group;
            md << "\n## " << group << "\n\n| name | unit | how it is computed |\n|---|---|---|\n";
        }
        md << "| `" << f.name << "` | " << f.unit << " | " << f.description << " |\n";
    }
    return md.str();
}

}  // namespace treelobes::classify
