// Throughput of DBF6 encoding, decoding and LOD reduction (seed 000 §3.1-3.2) on a
// deterministic random tree (about 1,000 internodes) from tests/encode/random_tree.hpp (switch to synth/
// species trees once they land). Run: bench_encode [--benchmark_filter=...]
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"
#include "tests/encode/random_tree.hpp"

#include <benchmark/benchmark.h>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

const TreeGraph& bench_tree() {
    static const TreeGraph tree = [] {
        test::RandomTreeProfile profile;
        profile.max_nodes = 4000;
        profile.trunk_internodes = 30;
        profile.wiggle_degrees = 8;
        profile.fork_probability = 0.35;
        profile.max_laterals = 2;
        profile.lateral_length_ratio = 0.8;
        profile.max_order = 6;
        return test::random_tree(profile, 42);
    }();
    return tree;
}

EncodeOptions options_for(double resolution) {
    EncodeOptions options;
    options.resolution = resolution;
    options.internode_length = 0.1;
    return options;
}

void BM_EncodeDbf6(benchmark::State& state) {
    const EncodeOptions options = options_for(static_cast<double>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(encode_tree(bench_tree(), options));
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(bench_tree().size() - 1));
}
BENCHMARK(BM_EncodeDbf6)->Arg(3)->Arg(5)->Arg(10)->Unit(benchmark::kMillisecond);

void BM_DecodeDbf6(benchmark::State& state) {
    const EncodedTree encoded = encode_tree(bench_tree(), options_for(static_cast<double>(state.range(0))));
    for (auto _ : state) benchmark::DoNotOptimize(decode_tree(encoded.code, encoded.geometry));
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(encoded.code.radii.size()));
    state.counters["symbols"] = static_cast<double>(encoded.code.symbols.size());
}
BENCHMARK(BM_DecodeDbf6)->Arg(3)->Arg(5)->Arg(10)->Unit(benchmark::kMillisecond);

void BM_LodChain(benchmark::State& state) {
    const EncodedTree encoded = encode_tree(bench_tree(), options_for(5.0));
    const std::vector<double> thresholds = lod_thresholds(encoded.code.radii, 4);
    for (auto _ : state) benchmark::DoNotOptimize(lod_chain(encoded.code, thresholds));
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(encoded.code.radii.size()));
}
BENCHMARK(BM_LodChain)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
