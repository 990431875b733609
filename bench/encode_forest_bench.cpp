// Decoding a compressed forest (Strnad et al. 2020, §4, Experiment 3: "decompression and decoding of the forest
// to maximum detail takes approximately 130 ms at r = 5"): LOD 0 of every tree of an in-memory
// .forest file to placed skeletons on one thread, for growing numbers of trees (linear scaling),
// and the two halves of the work separately (entropy decoding of the streams; chain code to
// skeleton). Trees: bench/compression_subjects.hpp forest_trees. Run:
//   bench_encode_forest [--benchmark_filter=...]
#include "bench/compression_subjects.hpp"
#include "encode/forest_file.hpp"

#include <benchmark/benchmark.h>

#include <map>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

constexpr int kLargestForest = 400;

const std::vector<ForestTree>& all_trees() {
    static const std::vector<ForestTree> trees = bench::forest_trees(kLargestForest);
    return trees;
}

// The .forest bytes of the first `count` trees at r = 5, one LOD.
const std::vector<std::uint8_t>& forest_bytes(int count, Coder coder) {
    static std::map<std::pair<int, Coder>, std::vector<std::uint8_t>> cache;
    auto& bytes = cache[{count, coder}];
    if (bytes.empty()) {
        const std::vector<ForestTree> trees(all_trees().begin(), all_trees().begin() + count);
        TreeFileOptions options;
        options.encode.resolution = 5.0;
        options.coder = coder;
        bytes = write_forest_bytes(trees, options);
    }
    return bytes;
}

std::size_t internodes_of(int count, Coder coder) {
    ForestReader reader(forest_bytes(count, coder), "forest");
    std::size_t n = 0;
    for (std::size_t i = 0; i < reader.size(); ++i) n += reader.read(i, 0).lods[0].radii.size();
    return n;
}

void decode_forest(benchmark::State& state, Coder coder) {
    const int count = static_cast<int>(state.range(0));
    const std::vector<std::uint8_t>& bytes = forest_bytes(count, coder);
    for (auto _ : state) {
        ForestReader reader(bytes, "forest");
        std::size_t nodes = 0;
        for (std::size_t i = 0; i < reader.size(); ++i) nodes += reader.decode(i, 0).size();
        benchmark::DoNotOptimize(nodes);
    }
    const auto internodes = static_cast<std::int64_t>(internodes_of(count, coder));
    state.SetItemsProcessed(state.iterations() * internodes);
    state.counters["internodes"] = static_cast<double>(internodes);
    state.counters["bytes"] = static_cast<double>(bytes.size());
}

void BM_DecodeForestBest(benchmark::State& state) { decode_forest(state, Coder::Best); }
void BM_DecodeForestIc(benchmark::State& state) { decode_forest(state, Coder::Interpolative); }
BENCHMARK(BM_DecodeForestBest)->Arg(50)->Arg(100)->Arg(200)->Arg(kLargestForest)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeForestIc)->Arg(kLargestForest)->Unit(benchmark::kMillisecond);

// Entropy decoding only (streams to chain codes), all trees.
void BM_DecodeStreamsOnly(benchmark::State& state) {
    const std::vector<std::uint8_t>& bytes = forest_bytes(kLargestForest, static_cast<Coder>(state.range(0)));
    for (auto _ : state) {
        ForestReader reader(bytes, "forest");
        std::size_t symbols = 0;
        for (std::size_t i = 0; i < reader.size(); ++i) symbols += reader.read(i, 0).lods[0].symbols.size();
        benchmark::DoNotOptimize(symbols);
    }
}
BENCHMARK(BM_DecodeStreamsOnly)
        ->Arg(static_cast<int>(Coder::Best))
        ->Arg(static_cast<int>(Coder::Interpolative))
        ->Unit(benchmark::kMillisecond);

// Chain code to skeleton only (decode_tree), all trees.
void BM_CodesToSkeletons(benchmark::State& state) {
    ForestReader reader(forest_bytes(kLargestForest, Coder::Best), "forest");
    std::vector<StoredTree> stored;
    for (std::size_t i = 0; i < reader.size(); ++i) stored.push_back(reader.read(i, 0));
    for (auto _ : state) {
        std::size_t nodes = 0;
        for (const StoredTree& t : stored) nodes += decode_stored_tree(t, 0, "forest").size();
        benchmark::DoNotOptimize(nodes);
    }
}
BENCHMARK(BM_CodesToSkeletons)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
