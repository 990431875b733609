#include "synth/mesh_sampling.hpp"

#include "core/angles.hpp"
#include "core/error.hpp"
#include "core/random.hpp"
#include "synth/scanner.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace treelobes::synth {

namespace {

constexpr std::size_t kMaxSamples = 50'000'000;
// Fractions of a scan's pulses expected to come back from a tree model: a first guess for the
// raster (a second scan corrects it when the guess was far off).
constexpr double kTlsHitFraction = 0.35;
constexpr double kAlsReturnsPerPulse = 0.6;

void add_wood_attribute(PointCloud& cloud) { cloud.add_extra("wood", AttributeType::UInt8).description = "1 wood, 0 leaf"; }

std::vector<double> cumulative_areas(const TriangleMesh& mesh) {
    std::vector<double> cumulative(mesh.faces.size());
    double sum = 0;
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        const auto& face = mesh.faces[f];
        const Eigen::Vector3d a = mesh.vertices[face[0]].cast<double>(), b = mesh.vertices[face[1]].cast<double>(),
                              c = mesh.vertices[face[2]].cast<double>();
        const double area = 0.5 * (b - a).cross(c - a).norm();
        sum += std::isfinite(area) ? area : 0.0;
        cumulative[f] = sum;
    }
    return cumulative;
}

void check_mesh(const TriangleMesh& mesh, const std::vector<std::uint8_t>& wood) {
    if (mesh.faces.empty()) throw Error::input("", "the mesh has no triangles to sample");
    if (wood.size() != mesh.faces.size()) throw Error(ExitCode::Internal, "sample_mesh: one wood label per face expected");
}

// Keeps `count` of the cloud's points, chosen at random, in their original order.
PointCloud thinned(const PointCloud& cloud, std::size_t count, std::uint64_t seed) {
    if (cloud.size() <= count) return cloud;
    std::vector<std::size_t> order(cloud.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    Rng rng(stream_seed(seed, 0x7814));
    for (std::size_t i = 0; i < count; ++i) std::swap(order[i], order[i + rng.below(order.size() - i)]);
    order.resize(count);
    std::sort(order.begin(), order.end());
    return cloud.subset(order);
}

// A scan's cloud with the sampling's attributes only (the scanner's tree labels mean nothing here).
PointCloud relabelled_scan(PointCloud scan) {
    std::erase_if(scan.extras, [](const ExtraAttribute& e) { return e.name != "wood"; });
    return scan;
}

Scene scene_of(const TriangleMesh& mesh, const std::vector<std::uint8_t>& wood) {
    Scene scene;
    scene.origin = mesh.origin;
    scene.meshes.push_back({mesh, wood});
    return scene;
}

PointCloud scan_tls_sized(const Scene& scene, const MeshSamplingOptions& o, MeshSamplingReport& report) {
    const auto [lo, hi] = scene.bounds();
    const double height = hi.z() - lo.z();
    const double across = (hi - lo).head<2>().norm();
    TlsOptions tls;
    tls.stations = o.stations;
    tls.station_distance_m = std::max({6.0, 0.6 * height, 0.5 * across + 3.0});
    tls.max_range_m = std::min(6000.0, 2.0 * (tls.station_distance_m + across + height) + 10.0);
    tls.min_elevation_deg = -90;
    // The model's angular window seen from a station (radians squared).
    const double d = tls.station_distance_m, eye = lo.z() + tls.station_height_m;
    const double azimuth_span = 2.0 * std::atan(0.5 * across / d);
    const double elevation_span = std::atan((hi.z() - eye) / d) - std::atan((lo.z() - eye) / d);
    const double window = std::max(1e-6, azimuth_span * elevation_span);
    auto step_for = [&](double points_per_pulse) {
        const double pulses = static_cast<double>(o.samples) / (o.stations * points_per_pulse);
        return std::clamp(std::sqrt(window / std::max(1.0, pulses)) / kRadiansPerDegree, 0.005, 5.0);
    };
    tls.angular_step_deg = step_for(kTlsHitFraction);
    ScanSummary summary;
    PointCloud cloud = scan_tls(scene, tls, o.seed, &summary);
    // A far-off guess (a sparse crown, a thin model): one more scan at the measured hit rate.
    const double hit_rate = static_cast<double>(cloud.size()) / std::max<std::uint64_t>(1, summary.pulses);
    if (cloud.size() < o.samples * 8 / 10 && hit_rate > 0 && tls.angular_step_deg > 0.005) {
        tls.angular_step_deg = step_for(hit_rate * 0.95);
        cloud = scan_tls(scene, tls, o.seed, &summary);
    }
    report.pulses = summary.pulses;
    report.angular_step_deg = tls.angular_step_deg;
    return cloud;
}

PointCloud scan_als_sized(const Scene& scene, const MeshSamplingOptions& o, MeshSamplingReport& report) {
    const auto [lo, hi] = scene.bounds();
    AlsOptions als;
    als.altitude_m = 300;
    const double half_width = 0.5 * (hi.x() - lo.x()) + 2.0;
    als.max_scan_angle_deg = std::clamp(std::atan(half_width / als.altitude_m) / kRadiansPerDegree, 0.5, 60.0);
    const double area = std::max(0.01, (hi.x() - lo.x()) * (hi.y() - lo.y()));
    auto density_for = [&](double points_per_pulse) {
        return std::clamp(static_cast<double>(o.samples) / (area * points_per_pulse), 0.01, 2000.0);
    };
    als.pulse_density = density_for(kAlsReturnsPerPulse);
    ScanSummary summary;
    PointCloud cloud = scan_als(scene, als, o.seed, &summary);
    const double per_pulse = static_cast<double>(cloud.size()) / std::max<std::uint64_t>(1, summary.pulses);
    // Pulses fly over the whole strip; count only those over the model's footprint.
    const double footprint_pulses = als.pulse_density * area;
    const double per_footprint_pulse = footprint_pulses > 0 ? static_cast<double>(cloud.size()) / footprint_pulses : per_pulse;
    if (cloud.size() < o.samples * 8 / 10 && per_footprint_pulse > 0 && als.pulse_density < 2000) {
        als.pulse_density = density_for(per_footprint_pulse * 0.95);
        cloud = scan_als(scene, als, o.seed, &summary);
    }
    report.pulses = summary.pulses;
    report.pulse_density = als.pulse_density;
    return cloud;
}

}  // namespace

SamplePattern parse_sample_pattern(const std::string& name) {
    if (name == "uniform") return SamplePattern::Uniform;
    if (name == "tls") return SamplePattern::Tls;
    if (name == "als") return SamplePattern::Als;
    throw Error::usage("unknown sampling '" + name + "' (expected uniform, tls or als)");
}

const char* sample_pattern_name(SamplePattern pattern) {
    switch (pattern) {
        case SamplePattern::Uniform:
            return "uniform";
        case SamplePattern::Tls:
            return "tls";
        case SamplePattern::Als:
            return "als";
    }
    return "uniform";
}

PointCloud sample_surface(const TriangleMesh& mesh, const std::vector<std::uint8_t>& wood, std::size_t count, std::uint64_t seed) {
    check_mesh(mesh, wood);
    const std::vector<double> cumulative = cumulative_areas(mesh);
    const double total = cumulative.back();
    if (!(total > 0)) throw Error::input("", "the mesh has no surface to sample (every triangle has zero area)");
    PointCloud cloud;
    cloud.origin = mesh.origin;
    add_wood_attribute(cloud);
    cloud.positions.reserve(count);
    cloud.classification.reserve(count);
    auto& labels = cloud.extras.front().values;
    labels.reserve(count);
    // Stratified along the cumulative area: sample k falls in the k-th of `count` equal slices of
    // the total area, at a random place within it. Every face gets its share of points up to one,
    // and the faces are visited in order (one sweep).
    Rng rng(stream_seed(seed, 0x5A3F));
    std::size_t face = 0;
    for (std::size_t k = 0; k < count; ++k) {
        const double target = (static_cast<double>(k) + rng.uniform()) / static_cast<double>(count) * total;
        while (face + 1 < cumulative.size() && cumulative[face] <= target) ++face;
        const auto& f = mesh.faces[face];
        const double s = std::sqrt(rng.uniform()), t = rng.uniform();
        const Eigen::Vector3d a = mesh.vertices[f[0]].cast<double>(), b = mesh.vertices[f[1]].cast<double>(),
                              c = mesh.vertices[f[2]].cast<double>();
        cloud.positions.push_back(((1 - s) * a + s * (1 - t) * b + s * t * c).cast<float>());
        cloud.classification.push_back(5);
        labels.push_back(wood[face]);
    }
    return cloud;
}

PointCloud sample_mesh(const TriangleMesh& mesh, const std::vector<std::uint8_t>& wood, const MeshSamplingOptions& options,
                       MeshSamplingReport* report) {
    check_mesh(mesh, wood);
    MeshSamplingOptions o = options;
    MeshSamplingReport local;
    MeshSamplingReport& r = report ? *report : local;
    r = {};
    r.surface_area = cumulative_areas(mesh).back();
    if (o.density > 0) {
        if (o.pattern != SamplePattern::Uniform) throw Error::usage("a sample density is for uniform sampling; scans take a sample count");
        o.samples = static_cast<std::size_t>(std::llround(std::min(o.density * r.surface_area, static_cast<double>(kMaxSamples))));
    }
    if (o.samples < 100 || o.samples > kMaxSamples)
        throw Error::usage("samples must be in [100, " + std::to_string(kMaxSamples) + "] (got " + std::to_string(o.samples) + ")");
    if (o.stations < 1 || o.stations > 16) throw Error::usage("stations must be in [1, 16]");

    PointCloud cloud;
    if (o.pattern == SamplePattern::Uniform) {
        cloud = sample_surface(mesh, wood, o.samples, o.seed);
    } else {
        const Scene scene = scene_of(mesh, wood);
        PointCloud scan = o.pattern == SamplePattern::Tls ? scan_tls_sized(scene, o, r) : scan_als_sized(scene, o, r);
        r.scanned_points = scan.size();
        if (scan.empty())
            throw Error::input("", std::string("the simulated ") + sample_pattern_name(o.pattern) + " scan saw nothing of the mesh");
        cloud = relabelled_scan(thinned(scan, o.samples, o.seed));
    }
    for (double v : cloud.extra("wood")->values) ++(v > 0.5 ? r.wood_points : r.leaf_points);
    return cloud;
}

}  // namespace treelobes::synth
