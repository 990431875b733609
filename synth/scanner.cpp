#include "synth/scanner.hpp"

#include "core/angles.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/random.hpp"
#include "synth/ray_scene.hpp"

#include <Eigen/Geometry>
#include <tbb/blocked_range.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace treelobes::synth {

namespace {

constexpr std::uint64_t kMaxPulses = 400'000'000;  // beyond this a scan takes hours: refuse

// A sub-ray of the beam pattern: offset on the unit disc (radius 1 = half the divergence).
struct BeamRay {
    double radius, angle, weight;
};

// Hexagonal rings: 1, 7, 19 or 37 rays; Gaussian weights (1/e^2 at the edge), summing to 1.
std::vector<BeamRay> beam_pattern(int sub_rays) {
    const int rings = sub_rays == 1 ? 0 : sub_rays == 7 ? 1 : sub_rays == 19 ? 2 : 3;
    std::vector<BeamRay> rays{{0.0, 0.0, 1.0}};
    for (int k = 1; k <= rings; ++k)
        for (int i = 0; i < 6 * k; ++i) {
            const double r = static_cast<double>(k) / rings;
            rays.push_back({r, 2 * std::numbers::pi * i / (6 * k), std::exp(-2.0 * r * r)});
        }
    double total = 0;
    for (const auto& r : rays) total += r.weight;
    for (auto& r : rays) r.weight /= total;
    return rays;
}

// One recorded return before labels are turned into attributes: only what the output keeps
// (scans of big trees hold tens of millions of these).
struct Sample {
    Eigen::Vector3f position;
    float energy;
    std::int32_t tree;  // index into Scene::trees, -1 = none
    std::int32_t internode;
    std::uint8_t return_number, returns;
    Surface surface;
};

struct SubHit {
    RayHit hit;
    float energy;
};

class PulseTracer {
public:
    PulseTracer(const RayScene& rays, const BeamOptions& beam) : rays_(rays), beam_(beam), pattern_(beam_pattern(beam.sub_rays)) {}

    // Fires one pulse and appends its detected returns to `out`.
    void fire(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_range, Rng& rng, std::vector<Sample>& out) {
        hits_.clear();
        const Eigen::Vector3d u = perpendicular(dir), v = dir.cross(u);
        const double half_angle = 0.5e-3 * beam_.divergence_mrad;
        const double spin = rng.uniform(0, 2 * std::numbers::pi);  // pattern orientation: no aliasing between pulses
        const Eigen::Vector3f o = origin.cast<float>();
        for (const BeamRay& b : pattern_) {
            const double a = b.angle + spin, off = std::tan(b.radius * half_angle);
            const Eigen::Vector3f d = (dir + off * (std::cos(a) * u + std::sin(a) * v)).normalized().cast<float>();
            RayHit hit;
            if (!rays_.intersect(o, d, 0.0f, static_cast<float>(max_range), hit)) continue;
            const float cosine = std::abs(hit.normal.dot(d));
            hits_.push_back({hit, static_cast<float>(b.weight) * hit.reflectance * cosine});
        }
        if (hits_.empty()) return;
        std::sort(hits_.begin(), hits_.end(), [](const SubHit& a, const SubHit& b) { return a.hit.t < b.hit.t; });
        group_returns(origin, dir, rng, out);
    }

private:
    static Eigen::Vector3d perpendicular(const Eigen::Vector3d& d) {
        const Eigen::Vector3d helper = std::abs(d.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
        return d.cross(helper).normalized();
    }

    // Hits within min_separation of a group's first hit merge into one return.
    void group_returns(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, Rng& rng, std::vector<Sample>& out) {
        const std::size_t first = out.size();
        std::size_t i = 0;
        while (i < hits_.size() && out.size() - first < static_cast<std::size_t>(beam_.max_returns)) {
            const float start = hits_[i].hit.t;
            double energy = 0, weighted_t = 0;
            std::size_t strongest = i;
            std::size_t j = i;
            for (; j < hits_.size() && hits_[j].hit.t - start < beam_.min_separation_m; ++j) {
                energy += hits_[j].energy;
                weighted_t += hits_[j].energy * hits_[j].hit.t;
                if (hits_[j].energy > hits_[strongest].energy) strongest = j;
            }
            if (energy >= beam_.detection_threshold && energy > 0) {
                const double range = weighted_t / energy + rng.normal(0.0, beam_.range_noise_m);
                const RayHit& hit = hits_[strongest].hit;
                out.push_back(
                        {(origin + dir * range).cast<float>(), static_cast<float>(energy), hit.tree, hit.internode, 0, 0, hit.surface});
            }
            i = j;
        }
        const auto count = static_cast<std::uint8_t>(out.size() - first);
        for (std::size_t k = first; k < out.size(); ++k) {
            out[k].return_number = static_cast<std::uint8_t>(k - first + 1);
            out[k].returns = count;
        }
    }

    const RayScene& rays_;
    BeamOptions beam_;
    std::vector<BeamRay> pattern_;
    std::vector<SubHit> hits_;
};

// Runs `lines` independent scan lines in parallel; line k draws from its own random stream and
// its samples are joined in line order, so the result does not depend on the thread count.
template <typename Line>
std::vector<Sample> run_lines(std::size_t lines, std::uint64_t seed, Line line) {
    std::vector<std::vector<Sample>> parts(lines);
    treelobes::parallel_for(tbb::blocked_range<std::size_t>(0, lines, 4), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
            Rng rng(stream_seed(seed, k));
            line(k, rng, parts[k]);
        }
    });
    std::vector<Sample> all;
    std::size_t total = 0;
    for (const auto& p : parts) total += p.size();
    all.reserve(total);
    for (auto& p : parts) {
        all.insert(all.end(), p.begin(), p.end());
        std::vector<Sample>().swap(p);  // release as we go: peak memory ~ one copy of the samples
    }
    return all;
}

std::uint8_t classification(Surface s) {
    switch (s) {
        case Surface::Ground:
            return 2;
        case Surface::Understory:
            return 3;
        case Surface::Wood:
        case Surface::Leaf:
            return 5;
    }
    return 1;
}

void add_label_attributes(PointCloud& cloud) {
    cloud.add_extra("treeID", AttributeType::Int32).description = "tree id, 0 = no tree";
    cloud.add_extra("species", AttributeType::UInt8).description = "species id, 0 = none";
    cloud.add_extra("wood", AttributeType::UInt8).description = "1 wood, 0 leaf or other";
    cloud.add_extra("internode", AttributeType::Int32, -1).description = "true skeleton node, -1 none";
}

PointCloud to_cloud(const Scene& scene, const std::vector<Sample>& samples) {
    PointCloud cloud;
    cloud.origin = scene.origin;
    const std::size_t n = samples.size();
    cloud.positions.reserve(n);
    cloud.intensity.reserve(n);
    cloud.return_number.reserve(n);
    cloud.number_of_returns.reserve(n);
    cloud.classification.reserve(n);
    add_label_attributes(cloud);
    for (auto& e : cloud.extras) e.values.reserve(n);
    for (const Sample& s : samples) {
        cloud.positions.push_back(s.position);
        cloud.intensity.push_back(static_cast<std::uint16_t>(std::lround(std::min(1.0f, s.energy) * 65535.0f)));
        cloud.return_number.push_back(s.return_number);
        cloud.number_of_returns.push_back(s.returns);
        cloud.classification.push_back(classification(s.surface));
        const bool tree = s.tree >= 0;
        const PlacedTree* placed = tree ? &scene.trees[static_cast<std::size_t>(s.tree)] : nullptr;
        cloud.extras[0].values.push_back(tree ? placed->tree_id : 0);
        cloud.extras[1].values.push_back(tree ? placed->tree.species_id : 0);
        cloud.extras[2].values.push_back(s.surface == Surface::Wood ? 1 : 0);
        cloud.extras[3].values.push_back(s.internode);
    }
    return cloud;
}

void check_options(const BeamOptions& b, const std::string& scanner) {
    const auto fail = [&](const std::string& what) { throw Error::usage(scanner + " beam: " + what); };
    if (!(b.divergence_mrad >= 0 && b.divergence_mrad <= 20)) fail("divergence must be in [0, 20] mrad");
    if (b.sub_rays != 1 && b.sub_rays != 7 && b.sub_rays != 19 && b.sub_rays != 37) fail("sub-rays must be 1, 7, 19 or 37");
    if (!(b.range_noise_m >= 0 && b.range_noise_m <= 1)) fail("range noise must be in [0, 1] m");
    if (b.max_returns < 1 || b.max_returns > 15) fail("max returns must be in [1, 15]");
    if (!(b.min_separation_m > 0 && b.min_separation_m <= 20)) fail("return separation must be in (0, 20] m");
    if (!(b.detection_threshold >= 0 && b.detection_threshold < 1)) fail("detection threshold must be in [0, 1)");
}

// Where the scanner points: the azimuth/elevation window that covers the scene box.
struct Window {
    double az0, az1, el0, el1;
};

Window tls_window(const Eigen::Vector3d& station, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const TlsOptions& o) {
    const bool inside = station.x() >= lo.x() && station.x() <= hi.x() && station.y() >= lo.y() && station.y() <= hi.y();
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    const double az_centre = std::atan2(centre.y() - station.y(), centre.x() - station.x());
    double daz0 = 0, daz1 = 0, el0 = std::numbers::pi / 2, el1 = -std::numbers::pi / 2;
    for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d p((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
        const Eigen::Vector3d d = p - station;
        double daz = std::atan2(d.y(), d.x()) - az_centre;
        daz = std::remainder(daz, 2 * std::numbers::pi);
        daz0 = std::min(daz0, daz), daz1 = std::max(daz1, daz);
        const double el = std::atan2(d.z(), d.head<2>().norm());
        el0 = std::min(el0, el), el1 = std::max(el1, el);
    }
    Window w;
    if (inside)
        w.az0 = -std::numbers::pi, w.az1 = std::numbers::pi;
    else
        w.az0 = az_centre + daz0, w.az1 = az_centre + daz1;
    w.el0 = std::max(inside ? -std::numbers::pi / 2 : el0, o.min_elevation_deg * kRadiansPerDegree);
    w.el1 = std::min(inside ? std::numbers::pi / 2 : el1, o.max_elevation_deg * kRadiansPerDegree);
    return w;
}

// An operator sets the tripod up beside a trunk, never inside one or on its root flare. A station
// that falls within `kTripodClearance` of a trunk's base (its flared root radius) is moved to the
// nearest spot that is clear of every trunk, searched on rings 0.25 m apart. Before, a grid of
// stations could stand inside a trunk (3 of the 66 synthetic plots of the terrestrial benches,
// docs/segment.md), and the scan then held hundreds of thousands of returns from the trunk's
// inner wall.
constexpr double kTripodClearance = 0.5;

bool clear_of_every_trunk(const Scene& scene, const Eigen::Vector2d& p) {
    return std::none_of(scene.trees.begin(), scene.trees.end(), [&](const PlacedTree& placed) {
        const double base_radius = placed.tree.skeleton.empty() ? 0.0 : placed.tree.skeleton.nodes[0].radius;
        return (p - placed.position.head<2>()).norm() < base_radius + kTripodClearance;
    });
}

Eigen::Vector2d clear_of_trunks(const Scene& scene, const Eigen::Vector2d& p) {
    constexpr int kDirections = 16;
    constexpr int kRings = 40;
    constexpr double kRingStep = 0.25;
    if (clear_of_every_trunk(scene, p)) return p;
    for (int ring = 1; ring <= kRings; ++ring)
        for (int k = 0; k < kDirections; ++k) {
            const double a = 2 * std::numbers::pi * k / kDirections;
            const Eigen::Vector2d candidate = p + ring * kRingStep * Eigen::Vector2d(std::cos(a), std::sin(a));
            if (clear_of_every_trunk(scene, candidate)) return candidate;
        }
    return p;  // no clear spot within 10 m: trunks that dense leave the tripod nowhere better
}

std::vector<Eigen::Vector3d> tls_stations(const Scene& scene, const TlsOptions& o, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                          std::uint64_t seed) {
    std::vector<Eigen::Vector2d> xy = o.station_xy;
    if (xy.empty()) {
        // Around the trees (not the ground patch), like an operator walking around a tree.
        Eigen::Vector2d centre = 0.5 * (lo + hi).head<2>();
        if (!scene.trees.empty()) {
            centre.setZero();
            for (const auto& t : scene.trees) centre += t.position.head<2>();
            centre /= static_cast<double>(scene.trees.size());
        }
        const double distance = o.station_distance_m > 0 ? o.station_distance_m : std::max(6.0, 0.6 * (hi.z() - lo.z()));
        const double phase = Rng(stream_seed(seed, 0x57A7)).uniform(0, 2 * std::numbers::pi);
        for (int k = 0; k < o.stations; ++k) {
            const double a = phase + 2 * std::numbers::pi * k / o.stations;
            xy.push_back(centre + distance * Eigen::Vector2d(std::cos(a), std::sin(a)));
        }
    }
    std::vector<Eigen::Vector3d> stations;
    for (Eigen::Vector2d p : xy) {
        p = clear_of_trunks(scene, p);
        const double ground = scene.ground ? scene.ground->height(p.x(), p.y()) : lo.z();
        stations.emplace_back(p.x(), p.y(), ground + o.station_height_m);
    }
    return stations;
}

}  // namespace

void check_options(const TlsOptions& o) {
    if (o.station_xy.empty() && (o.stations < 1 || o.stations > 16)) throw Error::usage("TLS stations must be 1..16");
    if (!(o.station_distance_m >= 0 && o.station_distance_m <= 500)) throw Error::usage("TLS station distance must be in [0, 500] m");
    if (!(o.station_height_m >= 0 && o.station_height_m <= 50)) throw Error::usage("TLS station height must be in [0, 50] m");
    if (!(o.angular_step_deg >= 0.005 && o.angular_step_deg <= 5)) throw Error::usage("TLS angular step must be in [0.005, 5] degrees");
    if (!(o.max_range_m > 0 && o.max_range_m <= 6000)) throw Error::usage("TLS max range must be in (0, 6000] m");
    if (!(o.min_elevation_deg >= -90 && o.min_elevation_deg < o.max_elevation_deg && o.max_elevation_deg <= 90))
        throw Error::usage("TLS elevation range must satisfy -90 <= min < max <= 90 degrees");
    check_options(o.beam, "TLS");
}

void check_options(const AlsOptions& o) {
    if (!(o.altitude_m >= 20 && o.altitude_m <= 6000)) throw Error::usage("ALS altitude must be in [20, 6000] m");
    if (!(o.pulse_density > 0 && o.pulse_density <= 2000)) throw Error::usage("ALS pulse density must be in (0, 2000] per m^2");
    if (!(o.max_scan_angle_deg > 0 && o.max_scan_angle_deg <= 60)) throw Error::usage("ALS scan angle must be in (0, 60] degrees");
    if (!(o.strip_overlap >= 0 && o.strip_overlap < 0.9)) throw Error::usage("ALS strip overlap must be in [0, 0.9)");
    if (!(o.jitter >= 0 && o.jitter <= 1)) throw Error::usage("ALS jitter must be in [0, 1]");
    check_options(o.beam, "ALS");
}

PointCloud scan_tls(const Scene& scene, const TlsOptions& o, std::uint64_t seed, ScanSummary* summary) {
    check_options(o);
    const auto [lo, hi] = scene.bounds();
    const RayScene rays(scene);
    const std::vector<Eigen::Vector3d> stations = tls_stations(scene, o, lo, hi, seed);
    const double step = o.angular_step_deg * kRadiansPerDegree;

    // Columns (one azimuth each) of all stations, numbered station by station.
    struct Column {
        std::size_t station;
        double azimuth;
        double el0;
        std::size_t rows;
    };
    std::vector<Column> columns;
    std::uint64_t pulses = 0;
    for (std::size_t s = 0; s < stations.size(); ++s) {
        const Window w = tls_window(stations[s], lo, hi, o);
        if (w.el1 <= w.el0) continue;
        const auto n_az = static_cast<std::size_t>(std::ceil((w.az1 - w.az0) / step));
        const auto n_el = static_cast<std::size_t>(std::ceil((w.el1 - w.el0) / step));
        pulses += static_cast<std::uint64_t>(n_az) * n_el;
        if (pulses > kMaxPulses)
            throw Error::usage("TLS scan would fire more than " + std::to_string(kMaxPulses) + " pulses; increase the angular step");
        for (std::size_t i = 0; i < n_az; ++i) columns.push_back({s, w.az0 + (i + 0.5) * step, w.el0 + 0.5 * step, n_el});
    }

    const std::vector<Sample> samples = run_lines(columns.size(), seed, [&](std::size_t k, Rng& rng, std::vector<Sample>& out) {
        PulseTracer tracer(rays, o.beam);
        const Column& c = columns[k];
        const double ca = std::cos(c.azimuth), sa = std::sin(c.azimuth);
        for (std::size_t r = 0; r < c.rows; ++r) {
            const double el = c.el0 + r * step;
            const Eigen::Vector3d dir(std::cos(el) * ca, std::cos(el) * sa, std::sin(el));
            tracer.fire(stations[c.station], dir, o.max_range_m, rng, out);
        }
    });
    if (summary) {
        summary->pulses = pulses;
        summary->rays = pulses * static_cast<std::uint64_t>(o.beam.sub_rays);
        summary->points = samples.size();
        summary->stations = stations;
    }
    return to_cloud(scene, samples);
}

PointCloud scan_als(const Scene& scene, const AlsOptions& o, std::uint64_t seed, ScanSummary* summary) {
    check_options(o);
    const auto bounds = scene.bounds();  // not a structured binding: clang 14 cannot capture those in lambdas
    const auto& lo = bounds.first;
    const auto& hi = bounds.second;
    const RayScene rays(scene);
    // Flight lines cover the ground (or the scene) plus a margin; returns outside are clipped.
    Eigen::Vector2d area_lo = lo.head<2>(), area_hi = hi.head<2>();
    if (scene.ground) {
        const Heightfield& g = *scene.ground;
        area_lo = Eigen::Vector2d(g.x0, g.y0);
        area_hi = Eigen::Vector2d(g.x0 + (g.nx - 1) * g.cell, g.y0 + (g.ny - 1) * g.cell);
    }
    const double top = scene.ground ? *std::max_element(scene.ground->z.begin(), scene.ground->z.end()) : lo.z();
    const double flying = top + o.altitude_m;
    const double spacing = 1.0 / std::sqrt(o.pulse_density);
    const double h = o.altitude_m;
    const double swath = 2.0 * h * std::tan(o.max_scan_angle_deg * kRadiansPerDegree);
    const double strip_step = swath * (1.0 - o.strip_overlap);
    const double width = area_hi.x() - area_lo.x();
    const int strips = std::max(1, static_cast<int>(std::ceil(width / strip_step)));
    const double first_strip = 0.5 * (area_lo.x() + area_hi.x()) - 0.5 * (strips - 1) * strip_step;
    const double margin = 2.0 * (hi.z() - lo.z()) * std::tan(o.max_scan_angle_deg * kRadiansPerDegree);
    const double y0 = area_lo.y() - margin, y1 = area_hi.y() + margin;
    const auto lines_per_strip = static_cast<std::size_t>(std::ceil((y1 - y0) / spacing));
    const double angle_step = spacing / h;  // nadir spacing on flat ground
    const auto per_line = static_cast<std::size_t>(std::floor(2.0 * o.max_scan_angle_deg * kRadiansPerDegree / angle_step)) + 1;
    const std::uint64_t pulses = static_cast<std::uint64_t>(strips) * lines_per_strip * per_line;
    if (pulses > kMaxPulses)
        throw Error::usage("ALS scan would fire more than " + std::to_string(kMaxPulses) + " pulses; lower the pulse density");

    std::vector<Sample> samples =
            run_lines(static_cast<std::size_t>(strips) * lines_per_strip, seed, [&](std::size_t k, Rng& rng, std::vector<Sample>& out) {
                PulseTracer tracer(rays, o.beam);
                const double x = first_strip + static_cast<double>(k / lines_per_strip) * strip_step;
                const double y = y0 + (static_cast<double>(k % lines_per_strip) + 0.5) * spacing;
                for (std::size_t j = 0; j < per_line; ++j) {
                    const double angle = -o.max_scan_angle_deg * kRadiansPerDegree + (j + rng.vary(o.jitter)) * angle_step;
                    const double yj = y + rng.vary(o.jitter) * spacing;
                    const Eigen::Vector3d dir(std::sin(angle), 0.0, -std::cos(angle));
                    tracer.fire(Eigen::Vector3d(x, yj, flying), dir, 2.0 * (flying - lo.z()) + 10.0, rng, out);
                }
            });
    // Keep what falls on the scanned area: pulses from the margins reach over its edges.
    std::erase_if(samples, [&](const Sample& s) {
        return s.position.x() < area_lo.x() || s.position.x() > area_hi.x() || s.position.y() < area_lo.y() || s.position.y() > area_hi.y();
    });
    if (summary) {
        summary->pulses = pulses;
        summary->rays = pulses * static_cast<std::uint64_t>(o.beam.sub_rays);
        summary->points = samples.size();
    }
    return to_cloud(scene, samples);
}

void add_outliers(PointCloud& cloud, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double fraction, std::uint64_t seed) {
    if (!(fraction >= 0 && fraction <= 0.5)) throw Error::usage("outlier fraction must be in [0, 0.5]");
    Rng rng(stream_seed(seed, 0x0D7));
    const auto count = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(cloud.size())));
    for (std::size_t i = 0; i < count; ++i) {
        // Drawn last coordinate first, in statements of their own: C++ leaves the order in which function
        // arguments are evaluated to the compiler (GCC right to left, Clang left to right), and this is the
        // order GCC gave the committed outputs.
        const double noise_z = rng.uniform(lo.z(), hi.z());
        const double noise_y = rng.uniform(lo.y(), hi.y());
        const double noise_x = rng.uniform(lo.x(), hi.x());
        const Eigen::Vector3d p(noise_x, noise_y, noise_z);
        cloud.positions.push_back(p.cast<float>());
        if (!cloud.intensity.empty()) cloud.intensity.push_back(static_cast<std::uint16_t>(rng.below(2000)));
        if (!cloud.return_number.empty()) cloud.return_number.push_back(1);
        if (!cloud.number_of_returns.empty()) cloud.number_of_returns.push_back(1);
        if (!cloud.classification.empty()) cloud.classification.push_back(7);
        for (auto& e : cloud.extras) e.values.push_back(e.name == "internode" ? -1.0 : 0.0);
    }
}

}  // namespace treelobes::synth
