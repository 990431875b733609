// Simulated laser scans of a synth::Scene, ray traced with Embree (synth/ray_scene.cpp).
//
// A pulse is a cone of `sub_rays` rays (hexagonal rings inside the beam divergence, Gaussian
// energy profile). Each sub-ray stops at the first surface it meets, so leaves and branches
// occlude what lies behind them; the far side and the inner crown get fewer points, as in real
// scans (Livny et al. 2011, §7). Sub-ray hits along the beam are grouped into returns: hits closer than
// `min_separation_m` merge (range = energy-weighted mean), groups whose energy (weight x
// reflectance x cos incidence) is below `detection_threshold` are not detected, at most
// `max_returns` are recorded. Each return is placed on the beam axis at its range plus Gaussian
// range noise. Labels come from the strongest hit of the return.
//
// Output PointCloud: positions in the scene frame + scene origin; intensity, return_number,
// number_of_returns, classification (2 ground, 3 low vegetation, 5 tree, 7 noise) and extras
//   treeID (int32, 0 = none), species (uint8, 0 = none), wood (uint8: 1 wood, 0 otherwise),
//   internode (int32: skeleton node whose internode (parent -> node) was hit; -1 = none).
// Pulses draw their randomness from per-pulse streams and results are joined in pulse order,
// so the cloud is identical for any number of threads.
#pragma once

#include "core/point_cloud.hpp"
#include "synth/scene.hpp"

#include <cstdint>
#include <vector>

namespace treelobes::synth {

struct BeamOptions {
    double divergence_mrad = 0.3;       // full angle of the beam (1/e^2 diameter)
    int sub_rays = 1;                   // 1, 7, 19 or 37 rays per pulse
    double range_noise_m = 0.005;       // Gaussian sigma along the beam
    int max_returns = 1;                // 1..15 recorded returns per pulse
    double min_separation_m = 0.5;      // hits closer than this make one return
    double detection_threshold = 0.02;  // energy a return needs (fraction of the pulse energy)
};

// Terrestrial scanner on a tripod: stations around the scene centre, a raster of pulses with
// equal angular steps in azimuth and elevation, limited to what faces the scene.
struct TlsOptions {
    int stations = 3;               // 1..16, evenly around the scene centre
    double station_distance_m = 0;  // 0: max(6, 0.6 x scene height)
    double station_height_m = 1.5;  // above the ground
    double angular_step_deg = 0.06;
    double max_range_m = 100;
    double min_elevation_deg = -60;
    double max_elevation_deg = 90;
    std::vector<Eigen::Vector2d> station_xy;  // explicit stations (scene frame); overrides the two above
    BeamOptions beam;
};

// Airborne scanner: parallel strips along y, a line-scanning mirror across track.
struct AlsOptions {
    double altitude_m = 500;         // above the highest point of the ground
    double pulse_density = 10;       // pulses per m^2 on flat ground within one strip
    double max_scan_angle_deg = 20;  // +- across track
    double strip_overlap = 0.2;      // fraction of the swath shared by neighbouring strips
    double jitter = 0.25;            // random pulse position jitter, fraction of the spacing
    BeamOptions beam{0.5, 19, 0.03, 5, 1.5, 0.05};
};

struct ScanSummary {
    std::uint64_t pulses = 0;
    std::uint64_t rays = 0;
    std::size_t points = 0;
    std::vector<Eigen::Vector3d> stations;  // TLS station positions (scene frame)
};

PointCloud scan_tls(const Scene& scene, const TlsOptions& options, std::uint64_t seed, ScanSummary* summary = nullptr);
PointCloud scan_als(const Scene& scene, const AlsOptions& options, std::uint64_t seed, ScanSummary* summary = nullptr);

// Adds `fraction * size()` uniformly scattered outliers (class 7, no tree) inside the box.
void add_outliers(PointCloud& cloud, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double fraction, std::uint64_t seed);

// Checks option ranges; throws Error(Usage) naming the option.
void check_options(const TlsOptions& options);
void check_options(const AlsOptions& options);

}  // namespace treelobes::synth
