// Feature extraction time per tree (target: <= 0.2 s per tree of 50k points): grows
// trees of several species, scans them (TLS), thins each scan evenly to 50,000 points and times
// classify::compute_features: wall time, process CPU time (all threads; on a loaded machine the
// CPU time is the steadier figure) and the wall time per feature group.
// Usage: bench_classify_features [POINTS] (default 50000)
#include "classify/features.hpp"
#include "config/species_profile.hpp"
#include "synth/scanner.hpp"

#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>

using namespace treelobes;

int main(int argc, char** argv) {
    std::size_t target = 50000;
    if (argc > 1) {
        char* end = nullptr;
        target = std::strtoul(argv[1], &end, 10);
        if (argc > 2 || *end != '\0' || target < 1000) {
            std::fprintf(stderr, "usage: bench_classify_features [POINTS >= 1000] (default 50000)\n");
            return 1;
        }
    }
    const auto profiles = load_species_profiles(default_species_file());
    double total = 0, total_cpu = 0;
    int trees = 0;
    std::printf("%-22s %8s %8s %8s %8s %8s %8s %8s %8s\n", "species", "points", "total_s", "cpu_s", "prepare", "points", "normals", "hull",
                "skeleton");
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
        for (double i = 0; i < static_cast<double>(scan.size()); i += step)
            cloud.positions.push_back(scan.positions[static_cast<std::size_t>(i)]);
        classify::FeatureTimings t;
        const auto start = std::chrono::steady_clock::now();
        const std::clock_t cpu_start = std::clock();
        classify::compute_features(cloud, {}, name, &t);
        const double cpu = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("%-22s %8zu %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f\n", name, cloud.size(), seconds, cpu, t.prepare, t.points,
                    t.normals, t.hull, t.skeleton);
        total += seconds, total_cpu += cpu, ++trees;
    }
    std::printf("mean %.3f s wall, %.3f s CPU per tree of ~%zu points\n", total / trees, total_cpu / trees, target);
    return 0;
}
