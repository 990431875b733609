// Lobes: time of the lobe stage after reconstruction (confidence, clusters, alpha
// shapes, simplification), of .tlobe coding, of lobe texturing and of LOD extraction
// (Livny et al. 2011, Table 2: reconstruction 3-18 ms, LOD 0.5-4 ms per tree on a GPU), on a real scan
// (archi/tree1_points.las from TREELOBES_REAL_DATA or ../shared/data).
// Whole-tree figures for every scan: bench/lobes_bench.sh and bench/lobes_species_bench.sh.
#include "config/species_profile.hpp"
#include "core/cloud_io.hpp"
#include "lobes/lobe_tree.hpp"
#include "lobes/synthesis.hpp"
#include "lobes/tlobe_io.hpp"

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>

using namespace treelobes;

namespace {

struct Fixture {
    PointCloud cloud;
    ReconstructOptions options;
    TreeReconstruction reconstruction;
    lobes::LobeTree built;  // as build_lobe_tree returns it (with the clusters' points)
    lobes::LobeTree tree;   // as `synthesize` reads it back from the .tlobe (with the occupancy)
    lobes::TexturedTree textured;
};

const Fixture& fixture() {
    static const Fixture f = [] {
        const char* env = std::getenv("TREELOBES_REAL_DATA");
        const std::filesystem::path data = env ? env : TREELOBES_DEFAULT_REAL_DATA;
        Fixture x;
        x.cloud = read_point_cloud(data / "archi" / "tree1_points.las");
        x.reconstruction = reconstruct_tree(x.cloud, x.options, "tree1_points");
        x.built = lobes::build_lobe_tree(x.cloud, x.reconstruction, x.options, "delonix");
        x.tree = lobes::decode_tlobe(lobes::encode_tlobe(x.built), "bench");
        static const auto profiles = load_species_profiles(default_species_file());
        x.textured = lobes::texture_tree(x.tree, find_species_profile(profiles, "delonix"));
        return x;
    }();
    return f;
}

void BM_LobeTree(benchmark::State& state) {
    const Fixture& f = fixture();
    for (auto _ : state) benchmark::DoNotOptimize(lobes::build_lobe_tree(f.cloud, f.reconstruction, f.options, "delonix"));
}

void BM_EncodeDecodeTlobe(benchmark::State& state) {
    const Fixture& f = fixture();
    for (auto _ : state) benchmark::DoNotOptimize(lobes::decode_tlobe(lobes::encode_tlobe(f.built), "bench"));
}

void BM_Texturing(benchmark::State& state) {
    const Fixture& f = fixture();
    static const auto profiles = load_species_profiles(default_species_file());
    for (auto _ : state) benchmark::DoNotOptimize(lobes::texture_tree(f.tree, find_species_profile(profiles, "delonix")));
}

void BM_LodExtraction(benchmark::State& state) {
    const Fixture& f = fixture();
    const double fraction = static_cast<double>(state.range(0)) / 100.0;
    std::size_t triangles = 0;
    for (auto _ : state) triangles = lobes::synthesized_mesh(f.tree, f.textured, fraction).triangles();
    state.counters["triangles"] = static_cast<double>(triangles);
}

}  // namespace

BENCHMARK(BM_LobeTree)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EncodeDecodeTlobe)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Texturing)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodExtraction)->Arg(10)->Arg(25)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
