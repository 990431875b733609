// Throughput of DBF6 encoding, decoding and LOD reduction (Strnad et al. 2020, §3.1-3.2), and of the range
// decoder's binary decisions, on a
// deterministic random tree (about 1,000 internodes) from tests/encode/random_tree.hpp (switch to synth/
// species trees once they land). Run: bench_encode [--benchmark_filter=...]
#include "encode/lod.hpp"
#include "core/range_coder.hpp"
#include "encode/tree_code.hpp"
#include "tests/encode/random_tree.hpp"

#include <benchmark/benchmark.h>

#include <random>

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
    const std::vector<double> thresholds = lod_thresholds(branch_thicknesses(encoded.code), 4);
    for (auto _ : state) benchmark::DoNotOptimize(lod_chain(encoded.code, thresholds));
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(encoded.code.radii.size()));
}
BENCHMARK(BM_LodChain)->Unit(benchmark::kMillisecond);

// Raw cost of one adaptive binary decision of the `best` coders' range decoder: 1 M decisions
// over 64 models with probabilities from 0.1 to 0.86 (0.85 bits each), decoded in a loop that
// does nothing else. The floor under the decisions the forest decoder makes (docs/forest.md).
void BM_RangeDecoderDecisions(benchmark::State& state) {
    constexpr int kDecisions = 1'000'000, kModels = 64;
    std::mt19937 random(1);
    std::vector<std::uint8_t> context(kDecisions);
    std::vector<bool> bits(kDecisions);
    for (int i = 0; i < kDecisions; ++i) {
        context[i] = static_cast<std::uint8_t>(random() % kModels);
        bits[i] = static_cast<int>(random() % 1000) < 100 + 12 * context[i];
    }
    RangeEncoder encoder;
    std::vector<BitModel> models(kModels);
    for (int i = 0; i < kDecisions; ++i) encoder.encode(models[context[i]], bits[i]);
    const std::vector<std::uint8_t> bytes = encoder.finish();
    for (auto _ : state) {
        std::vector<BitModel> decoding(kModels);
        const std::string name = "bench";
        RangeDecoder decoder(bytes, name);
        int ones = 0;
        for (int i = 0; i < kDecisions; ++i) ones += decoder.decode(decoding[context[i]]);
        benchmark::DoNotOptimize(ones);
    }
    state.SetItemsProcessed(state.iterations() * kDecisions);
}
BENCHMARK(BM_RangeDecoderDecisions)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
