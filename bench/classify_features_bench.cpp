// Feature extraction time per tree (issue 9 target: <= 0.2 s per tree of 50k points): grows
// trees of several species, scans them (TLS), thins each scan evenly to 50,000 points and times
// classify::compute_features, with the time per feature group.
// Usage: bench_classify_features [POINTS] (default 50000)
#include "classify/features.hpp"
#include "config/species_profile.hpp"
#include "synth/scanner.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>

using namespace treelobes;

int main(int argc, char** argv) {
    const std::size_t target = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 50000;
    const auto profiles = load_species_profiles(default_species_file());
    double total = 0;
    int trees = 0;
    std::printf("%-22s %8s %8s %8s %8s %8s %8s %8s\n", "species", "points", "total_s", "prepare", "points", "normals", "hull", "skeleton");
    for (const char* name : {"pine", "oak", "palm", "birch", "willow", "ficus_virens"}) {
        synth::GrowOptions grow;
        grow.height_m = 12;
        grow.max_leaves = 20000;
        synth::Scene scene;
        scene.trees.push_back({synth::grow(find_species_profile(profiles, name), 1, grow), Eigen::Vector3d::Zero(), 1});
        scene.ground = synth::make_ground(-10, -10, 10, 10, 0, 0, 0.02, 1);
        synth::TlsOptions tls;
        tls.angular_step_deg = 0.1;
        const PointCloud scan = synth::scan_tls(scene, tls, 1);
        PointCloud cloud;
        const double step = std::max(1.0, static_cast<double>(scan.size()) / static_cast<double>(target));
        for (double i = 0; i < static_cast<double>(scan.size()); i += step) cloud.positions.push_back(scan.positions[static_cast<std::size_t>(i)]);
        classify::FeatureTimings t;
        const auto start = std::chrono::steady_clock::now();
        classify::compute_features(cloud, {}, name, &t);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("%-22s %8zu %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f\n", name, cloud.size(), seconds, t.prepare, t.points, t.normals, t.hull,
                    t.skeleton);
        total += seconds, ++trees;
    }
    std::printf("mean %.3f s per tree of ~%zu points\n", total / trees, target);
    return 0;
}
