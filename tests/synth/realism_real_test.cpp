// Do simulated scans look like real ones? A simulated TLS pine against TreeLS's pine.las (height
// profile of the points around the stem, noise of the stem surface) and a simulated ALS forest
// tile against lidR's Megaplot.las (points per m^2, return-number mix). Label `real`.
#include "config/species_profile.hpp"
#include "core/cloud_io.hpp"
#include "support/test_support.hpp"
#include "synth/scan_stats.hpp"
#include "synth/scanner.hpp"
#include "synth/tile.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <numeric>

using namespace treelobes;

namespace {

std::string format_profile(const std::vector<double>& p) {
    std::string s;
    char v[16];
    for (double x : p) std::snprintf(v, sizeof v, " %.3f", x), s += v;
    return s;
}

// pine.las is a column of +-1.24 m around the stem: compare the same column of both.
constexpr double kColumn = 1.24;

}  // namespace

TEST(RealismReal, TlsPineLooksLikeTreeLsPine) {
    const auto file = test::real_data("treels/pine.las");
    if (file.empty()) return;
    const PointCloud real = read_las(file);
    const auto [lo, hi] = real.bounds();
    const Eigen::Vector2d real_centre = real.origin.head<2>() + 0.5 * (lo + hi).head<2>().cast<double>();
    const synth::StemFit real_stem = synth::fit_stem(real, real_centre, kColumn);

    // A 20 m pine like the real one, scanned with the default TLS settings.
    const auto library = load_species_profiles(default_species_file());
    synth::GrowOptions grow;
    grow.height_m = 20;
    const synth::Scene scene = synth::single_tree_scene(synth::grow(find_species_profile(library, "pine"), 1, grow), 2.0, 1);
    // pine.las was thinned to a 1 cm grid (its nearest neighbours are exactly 1 cm apart): the
    // simulated scan is thinned the same way, or its near-scanner density would dominate.
    const PointCloud sim = synth::voxel_thin(synth::scan_tls(scene, synth::TlsOptions{}, 1), 0.01);
    const synth::StemFit sim_stem = synth::fit_stem(sim, Eigen::Vector2d::Zero(), kColumn);

    const auto real_profile = synth::height_profile(real, real_stem.centre, kColumn, 10);
    const auto sim_profile = synth::height_profile(sim, sim_stem.centre, kColumn, 10);
    const std::vector<double> uniform(10, 0.1);
    const double distance = synth::profile_distance(real_profile, sim_profile);
    std::printf("pine.las   profile%s  stem r %.3f m, rms %.4f m (%zu pts)\n", format_profile(real_profile).c_str(), real_stem.radius,
                real_stem.rms, real_stem.points);
    std::printf("simulated  profile%s  stem r %.3f m, rms %.4f m (%zu pts)\n", format_profile(sim_profile).c_str(), sim_stem.radius,
                sim_stem.rms, sim_stem.points);
    std::printf("profile L1 distance %.3f (real vs uniform %.3f); stem noise ratio %.2f\n", distance,
                synth::profile_distance(real_profile, uniform), sim_stem.rms / real_stem.rms);
    RecordProperty("profile_distance", std::to_string(distance));
    RecordProperty("stem_rms_real", std::to_string(real_stem.rms));
    RecordProperty("stem_rms_sim", std::to_string(sim_stem.rms));

    EXPECT_LT(distance, 0.25);
    // Crown versus bole: the upper half of the height range holds about as much of the scan.
    const auto upper = [](const std::vector<double>& p) { return std::accumulate(p.begin() + 5, p.end(), 0.0); };
    EXPECT_NEAR(upper(sim_profile), upper(real_profile), 0.1);
    EXPECT_GT(sim_stem.rms, 0.5 * real_stem.rms);
    EXPECT_LT(sim_stem.rms, 2.0 * real_stem.rms);
    EXPECT_GT(sim_stem.points, 200u);
}

TEST(RealismReal, AlsTileLooksLikeMegaplot) {
    const auto file = test::real_data("lidr/Megaplot.las");
    if (file.empty()) return;
    const synth::ReturnMix real = synth::return_mix(read_las(file));

    // A closed forest (150 stems/ha, like a managed stand) flown at about Megaplot's first-return
    // density (~1 pulse per m^2).
    const auto library = load_species_profiles(default_species_file());
    synth::TileOptions t;
    t.trees = 96;
    t.size_m = 80;
    t.grow.max_leaves = 20000;
    const synth::Tile tile = synth::make_tile(library, 1, t);
    synth::AlsOptions als;
    als.pulse_density = 1.0;
    const synth::ReturnMix sim = synth::return_mix(synth::scan_als(tile.scene, als, 1));

    std::printf("Megaplot   %.2f pts/m2 (%.2f first), returns 1/2/3/4+: %.3f %.3f %.3f %.3f\n", real.points_per_m2,
                real.first_returns_per_m2, real.by_return[0], real.by_return[1], real.by_return[2], real.by_return[3]);
    std::printf("simulated  %.2f pts/m2 (%.2f first), returns 1/2/3/4+: %.3f %.3f %.3f %.3f\n", sim.points_per_m2, sim.first_returns_per_m2,
                sim.by_return[0], sim.by_return[1], sim.by_return[2], sim.by_return[3]);
    RecordProperty("points_per_m2_real", std::to_string(real.points_per_m2));
    RecordProperty("points_per_m2_sim", std::to_string(sim.points_per_m2));

    EXPECT_GT(sim.points_per_m2, 0.6 * real.points_per_m2);
    EXPECT_LT(sim.points_per_m2, 1.6 * real.points_per_m2);
    EXPECT_NEAR(sim.by_return[0], real.by_return[0], 0.1);
    EXPECT_NEAR(sim.by_return[1], real.by_return[1], 0.1);
    EXPECT_LT(sim.by_return[3], 0.05);
}
