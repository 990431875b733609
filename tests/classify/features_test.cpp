// Shape features on small simulated scans (synth: grown trees, coarse TLS): the catalogue and its
// documentation, invariance to position and heading, robustness to thinning, determinism and
// the rejection of clouds that are not trees.
#include "classify/features.hpp"
#include "config/species_profile.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/random.hpp"
#include "support/species_profiles.hpp"
#include "support/test_support.hpp"
#include "synth/scanner.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

using namespace treelobes;
using treelobes::test::species_profiles;
using namespace treelobes::classify;

namespace {

// One tree of `species` on a small ground patch, scanned from three TLS stations at 0.4 deg
// (about a hundred thousand points: a realistic single-tree scan, a few seconds to make).
PointCloud scanned_tree(const std::string& species, double height, std::uint64_t seed) {
    synth::GrowOptions grow;
    grow.height_m = height;
    grow.max_leaves = 6000;
    synth::Scene scene;
    scene.trees.push_back({synth::grow(find_species_profile(species_profiles(), species), seed, grow), Eigen::Vector3d::Zero(), 1});
    scene.ground = synth::make_ground(-8, -8, 8, 8, 0, 0, 0.02, seed);
    synth::TlsOptions tls;
    tls.angular_step_deg = 0.4;
    return synth::scan_tls(scene, tls, seed);
}

// The same tree seen from the air (synth ALS: returns, intensity, classes, ground), a few hundred points.
PointCloud airborne_tree(const std::string& species, std::uint64_t seed) {
    synth::GrowOptions grow;
    grow.height_m = 12.0;
    grow.max_leaves = 6000;
    synth::Scene scene;
    scene.trees.push_back({synth::grow(find_species_profile(species_profiles(), species), seed, grow), Eigen::Vector3d::Zero(), 1});
    scene.ground = synth::make_ground(-10, -10, 10, 10, 0, 0, 0.02, seed);
    synth::AlsOptions als;
    als.pulse_density = 20;
    return synth::scan_als(scene, als, seed);
}

// Cached scans: each is made once per test program.
const PointCloud& tree(const std::string& species, std::uint64_t seed = 1) {
    static std::map<std::pair<std::string, std::uint64_t>, PointCloud> cache;
    auto it = cache.find({species, seed});
    if (it == cache.end()) it = cache.emplace(std::make_pair(species, seed), scanned_tree(species, 9.0, seed)).first;
    return it->second;
}

// The scan moved and turned, with its attributes (classes, returns, intensity).
PointCloud transformed(const PointCloud& cloud, double heading_deg, const Eigen::Vector3f& shift) {
    const Eigen::Matrix3f turn =
            Eigen::AngleAxisf(static_cast<float>(heading_deg * M_PI / 180), Eigen::Vector3f::UnitZ()).toRotationMatrix();
    PointCloud out = cloud;
    for (auto& p : out.positions) p = turn * p + shift;
    return out;
}

PointCloud random_half(const PointCloud& cloud, std::uint64_t seed) {
    Rng rng(seed);
    std::vector<bool> keep(cloud.size());
    for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = rng.uniform(0, 1) < 0.5;
    return cloud.subset(keep);
}

// Equal vectors, a missing value (NaN) matching only a missing value.
bool same_vector(const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t f = 0; f < a.size(); ++f)
        if (!(a[f] == b[f] || (std::isnan(a[f]) && std::isnan(b[f])))) return false;
    return true;
}

// Per feature, a scale to compare differences with: the spread of the feature over a few trees
// of different species (features that are constant there get the absolute floor).
std::vector<double> feature_scales(const std::vector<std::vector<double>>& vectors) {
    std::vector<double> scale(vectors.front().size(), 0.0);
    for (std::size_t f = 0; f < scale.size(); ++f) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (const auto& v : vectors)
            if (!std::isnan(v[f])) lo = std::min(lo, v[f]), hi = std::max(hi, v[f]);
        scale[f] = hi >= lo ? std::max(hi - lo, 1e-3 * std::max(1.0, std::abs(hi))) : 1.0;
    }
    return scale;
}

// Mean over features of |a - b| / scale: 0 for equal vectors, about 0.3-0.5 between species.
double scaled_distance(const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& scale) {
    double sum = 0;
    for (std::size_t f = 0; f < a.size(); ++f) {
        if (std::isnan(a[f]) || std::isnan(b[f]))
            sum += std::isnan(a[f]) && std::isnan(b[f]) ? 0.0 : 1.0;  // missing in one only: as far as it gets
        else
            sum += std::min(1.0, std::abs(a[f] - b[f]) / scale[f]);
    }
    return sum / static_cast<double>(a.size());
}

const std::vector<std::string> kSpecies = {"pine", "oak", "palm", "willow"};

const std::vector<std::vector<double>>& species_vectors() {
    static const std::vector<std::vector<double>> v = [] {
        std::vector<std::vector<double>> out;
        for (const auto& s : kSpecies) out.push_back(compute_features(tree(s)));
        return out;
    }();
    return v;
}

}  // namespace

TEST(ClassifyFeatures, CatalogueHasMoreThan200DocumentedUniqueFeatures) {
    const auto& catalogue = feature_catalogue();
    EXPECT_GT(catalogue.size(), 200u);
    std::set<std::string> names;
    const std::set<std::string> units = {"m", "m^2", "deg", "1", "count", "1/m", "1/m^2"};
    for (const auto& f : catalogue) {
        EXPECT_TRUE(names.insert(f.name).second) << "duplicate feature " << f.name;
        EXPECT_TRUE(units.count(f.unit)) << f.name << " has unit '" << f.unit << "'";
        EXPECT_GE(f.description.size(), 10u) << f.name;
        EXPECT_FALSE(f.group.empty()) << f.name;
        EXPECT_EQ(f.name.find(','), std::string::npos) << "a CSV column name cannot hold a comma: " << f.name;
    }
    // The paper's list (Livny et al. 2011, §6.1) and the skeleton features from a first reconstruction are all there.
    for (const char* required : {"trunk_diameter",
                                 "height",
                                 "crown_width_major",
                                 "crown_width_minor",
                                 "width_height_ratio",
                                 "normal_elevation_00",
                                 "normal_axis_angle_00",
                                 "z_moment2",
                                 "z_moment3",
                                 "z_moment4",
                                 "z_decile_05",
                                 "count_cv_20",
                                 "stems_at_05",
                                 "skel_angle_o1_mean",
                                 "skel_length_o2_mean",
                                 "skel_radius_o1_mean",
                                 "skel_whorl_spacing_mean",
                                 "skel_tip_offset_ratio",
                                 "alpha_hull_ratio_20",
                                 "boxcount_dimension",
                                 "skel_boxcount_dimension"})
        EXPECT_TRUE(names.count(required)) << "missing feature " << required;
    EXPECT_EQ(feature_names().size(), catalogue.size());
}

TEST(ClassifyFeatures, CommittedDocumentationMatchesTheCatalogue) {
    const auto path = test::source_dir() / "docs" / "features.md";
    ASSERT_TRUE(std::filesystem::exists(path)) << path << " is missing: treelobes classify features --list > docs/features.md";
    EXPECT_EQ(read_file(path), features_markdown())
            << "docs/features.md is out of date: regenerate it with treelobes classify features --list > docs/features.md";
}

double feature(const std::vector<double>& v, const std::string& name) {
    const auto names = feature_names();
    return v[std::find(names.begin(), names.end(), name) - names.begin()];
}

TEST(ClassifyFeatures, InvariantToPositionAndHeading) {
    const auto& vectors = species_vectors();
    const auto scale = feature_scales(vectors);
    for (std::size_t s = 0; s < 2; ++s) {
        SCOPED_TRACE(kSpecies[s]);
        const auto& original = vectors[s];
        const auto moved = compute_features(transformed(tree(kSpecies[s]), 37, {120.0f, -80.0f, 15.0f}));
        const auto turned = compute_features(transformed(tree(kSpecies[s]), 200, {0.0f, 0.0f, 0.0f}));
        const auto half = compute_features(random_half(tree(kSpecies[s]), 4));
        // The frame turns and moves with the tree, so only float rounding changes anything; for
        // a nearly round crown the principal axes (and with them the voxel grid) are ill-
        // conditioned and the voxel points are resampled: still well below what thinning does.
        const double limit = std::max(0.01, 0.5 * scaled_distance(original, half, scale));
        EXPECT_LT(scaled_distance(original, moved, scale), limit);
        EXPECT_LT(scaled_distance(original, turned, scale), limit);
        for (const char* name : {"height", "crown_radius", "trunk_diameter", "z_decile_05", "width_height_ratio"}) {
            EXPECT_NEAR(feature(moved, name), feature(original, name), 0.02 * std::abs(feature(original, name)) + 1e-6) << name;
            EXPECT_NEAR(feature(turned, name), feature(original, name), 0.02 * std::abs(feature(original, name)) + 1e-6) << name;
        }
    }
}

TEST(ClassifyFeatures, NearlyTheSameVectorAtHalfTheDensity) {
    const auto& vectors = species_vectors();
    const auto scale = feature_scales(vectors);
    double between = 1.0;
    for (std::size_t a = 0; a < vectors.size(); ++a)
        for (std::size_t b = a + 1; b < vectors.size(); ++b) between = std::min(between, scaled_distance(vectors[a], vectors[b], scale));
    EXPECT_GT(between, 0.3) << "the test species should be far apart";
    for (std::size_t s = 0; s < 2; ++s) {
        SCOPED_TRACE(kSpecies[s]);
        const auto half = compute_features(random_half(tree(kSpecies[s]), 4));
        // Thinning moves the vector by a fraction of the distance between species (measured:
        // 0.11-0.16 against 0.45; the skeleton and occupancy features move most).
        EXPECT_LT(scaled_distance(vectors[s], half, scale), 0.4 * between);
        for (const char* name : {"height", "crown_radius", "crown_width_major", "width_height_ratio", "z_decile_03", "z_decile_07",
                                 "profile_shape_10", "hull_cylinder_ratio"})
            EXPECT_NEAR(feature(half, name), feature(vectors[s], name), 0.05 * std::abs(feature(vectors[s], name)) + 1e-3) << name;
    }
}

// The scan descriptor follows the point density on purpose (it routes trees to the model of
// their scan kind) and nothing else: the same tree moved or turned keeps it, half the points
// halve it. It is the only feature whose name is_scan_descriptor() accepts.
TEST(ClassifyFeatures, ScanDensityHalvesWithHalfThePointsAndIgnoresPose) {
    const auto& vectors = species_vectors();
    for (std::size_t s = 0; s < 2; ++s) {
        SCOPED_TRACE(kSpecies[s]);
        const double full = feature(vectors[s], kScanDensityFeature);
        const auto cloud = tree(kSpecies[s]);
        const double per_disc = static_cast<double>(extract_crown(cloud).crown.size()) /
                                (3.14159265358979 * std::pow(feature(vectors[s], "crown_radius"), 2));
        EXPECT_NEAR(full, per_disc, 1e-6 * per_disc);
        EXPECT_GT(full, 1000.0) << "a terrestrial scan";
        const auto turned = compute_features(transformed(cloud, 37, {120.0f, -80.0f, 15.0f}));
        EXPECT_NEAR(feature(turned, kScanDensityFeature), full, 0.03 * full);
        const double half = feature(compute_features(random_half(cloud, 4)), kScanDensityFeature);
        EXPECT_GT(half, 0.45 * full);
        EXPECT_LT(half, 0.55 * full);
    }
    int descriptors = 0;
    for (const auto& name : feature_names()) descriptors += is_scan_descriptor(name);
    EXPECT_EQ(descriptors, 1);
    EXPECT_TRUE(is_scan_descriptor(kScanDensityFeature));
}

TEST(ClassifyFeatures, DeterministicAndSkeletonGroupCanBeSkipped) {
    const auto& cloud = tree("palm");
    EXPECT_TRUE(same_vector(compute_features(cloud), species_vectors()[2]));
    FeatureOptions fast;
    fast.skeleton = false;
    const auto without = compute_features(cloud, fast);
    const auto& catalogue = feature_catalogue();
    ASSERT_EQ(without.size(), catalogue.size());
    int skeleton_nonzero = 0;
    for (std::size_t f = 0; f < catalogue.size(); ++f) {
        if (catalogue[f].group == "skeleton") {
            EXPECT_EQ(without[f], 0.0) << catalogue[f].name;
        } else {
            EXPECT_TRUE(same_vector({without[f]}, {species_vectors()[2][f]})) << catalogue[f].name;
        }
        skeleton_nonzero += catalogue[f].group == "skeleton" && species_vectors()[2][f] != 0.0;
    }
    // The pine (branches in whorls) fills the skeleton group; the palm's skeleton is a bare trunk.
    int pine_nonzero = 0;
    for (std::size_t f = 0; f < catalogue.size(); ++f) pine_nonzero += catalogue[f].group == "skeleton" && species_vectors()[0][f] != 0.0;
    EXPECT_GT(skeleton_nonzero, 10) << "the full extraction fills the skeleton group";
    EXPECT_GT(pine_nonzero, 30) << "the full extraction fills the skeleton group";
}

TEST(ClassifyFeatures, PlausibleValuesForAKnownTree) {
    // The pine was grown 9 m tall with one stem; the scan includes the ground patch.
    const auto& v = species_vectors()[0];
    EXPECT_NEAR(feature(v, "height"), 9.0, 1.0);
    EXPECT_EQ(feature(v, "stems_at_05"), 1.0);
    EXPECT_GT(feature(v, "trunk_diameter"), 0.05);
    EXPECT_LT(feature(v, "trunk_diameter"), 0.6);
    double zhist = 0;
    for (int k = 0; k < 20; ++k) zhist += feature(v, (k < 10 ? "zhist_0" : "zhist_") + std::to_string(k));
    EXPECT_NEAR(zhist, 1.0, 1e-9);
    const auto& catalogue = feature_catalogue();
    for (std::size_t f = 0; f < v.size(); ++f)
        if (catalogue[f].group != "airborne") {
            EXPECT_TRUE(std::isfinite(v[f])) << catalogue[f].name;
        }
}

TEST(ClassifyFeatures, RejectsCloudsThatAreNotTrees) {
    // A few points are a small crown, not an error: the shape groups are missing (tests/classify/crown_test.cpp).
    PointCloud few;
    for (int i = 0; i < 20; ++i) few.positions.emplace_back(i * 0.1f, 0.0f, i * 0.2f);
    EXPECT_TRUE(std::isnan(feature(compute_features(few, {}, "few.xyz"), "height")));
    PointCloud flat;
    Rng rng(2);
    for (int i = 0; i < 2000; ++i) {
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const auto z = static_cast<float>(rng.normal(0, 0.02));
        const auto y = static_cast<float>(rng.uniform(0, 10));
        const auto x = static_cast<float>(rng.uniform(0, 10));
        flat.positions.emplace_back(x, y, z);
    }
    try {
        compute_features(flat, {}, "lawn.xyz");
        FAIL() << "a flat patch gave features";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("lawn.xyz"), std::string::npos);
    }
}

// The airborne group (height above ground, density profile, intensity, returns, crown top) from ALS
// scans: moved and turned it stays (float rounding and the 1 m raster's cell boundaries aside), and
// half the points move it by much less than the difference between species.
TEST(ClassifyFeatures, AirborneGroupInvariantToPositionHeadingAndDensity) {
    const auto names = feature_names();
    const auto& catalogue = feature_catalogue();
    std::vector<std::size_t> group;
    for (std::size_t f = 0; f < catalogue.size(); ++f)
        if (catalogue[f].group == "airborne" && catalogue[f].name.rfind("als_rgb", 0) != 0) group.push_back(f);
    ASSERT_GE(group.size(), 25u);
    const auto airborne = [&](const std::vector<double>& v) {
        std::vector<double> out;
        for (auto f : group) out.push_back(v[f]);
        return out;
    };
    std::vector<PointCloud> scans;
    std::vector<std::vector<double>> vectors;
    for (const auto& s : kSpecies) {
        scans.push_back(airborne_tree(s, 2));
        vectors.push_back(airborne(compute_features(scans.back())));
        // ALS scans have every attribute but colour (an empty layer, e.g. under a palm's crown, is missing).
        const auto full = compute_features(scans.back());
        for (const char* name : {"als_height", "als_crown_radius", "als_crown_area", "als_layer_share_00", "als_intensity_ground_ratio",
                                 "als_intensity_cv", "als_single_share", "als_first_share", "als_ground_share", "als_top_drop_mean"})
            EXPECT_TRUE(std::isfinite(feature(full, name))) << s << ": " << name;
    }
    const auto scale = feature_scales(vectors);
    double between = 1.0;
    for (std::size_t a = 0; a < vectors.size(); ++a)
        for (std::size_t b = a + 1; b < vectors.size(); ++b) between = std::min(between, scaled_distance(vectors[a], vectors[b], scale));
    for (std::size_t s = 0; s < 2; ++s) {
        SCOPED_TRACE(kSpecies[s]);
        PointCloud moved = scans[s], turned = scans[s];
        const Eigen::Matrix3f turn37 =
                Eigen::AngleAxisf(37.0f * static_cast<float>(M_PI) / 180, Eigen::Vector3f::UnitZ()).toRotationMatrix();
        const Eigen::Matrix3f turn200 =
                Eigen::AngleAxisf(200.0f * static_cast<float>(M_PI) / 180, Eigen::Vector3f::UnitZ()).toRotationMatrix();
        for (auto& p : moved.positions) p = turn37 * p + Eigen::Vector3f(120.0f, -80.0f, 15.0f);
        for (auto& p : turned.positions) p = turn200 * p;
        std::vector<bool> keep(scans[s].size());
        Rng rng(4);
        for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = rng.uniform(0, 1) < 0.5;
        const auto half = airborne(compute_features(scans[s].subset(keep)));
        EXPECT_LT(scaled_distance(vectors[s], airborne(compute_features(moved)), scale), 0.05);
        EXPECT_LT(scaled_distance(vectors[s], airborne(compute_features(turned)), scale), 0.05);
        EXPECT_LT(scaled_distance(vectors[s], half, scale), 0.5 * between) << "between species " << between;
        EXPECT_NEAR(half[0], vectors[s][0], 0.05 * vectors[s][0]) << "als_height";
        EXPECT_NEAR(half[1], vectors[s][1], 0.15 * vectors[s][1]) << "als_crown_radius";
    }
}
