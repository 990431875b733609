// LOD extraction from multiresolution chains (Lluch et al. 2010, via Ong's seminar report, §3.3): the time to turn
// the chain prefix of every tree of a forest into skeletons, for 100 and 2,000 trees, against
// interpreting the full strings (the "geometric model"). Lluch et al. 2010 report 69 fps (hybrid) against
// 3 fps (full geometry) for 100 trees and 6 against 0.1 fps for 2,000 trees, rendering included;
// here only the branch geometry is produced (no rendering, no foliage).
//
// The forest cycles through the example L-systems with varied parameters (every tree differs):
// Honda's monopodial tree (n = 8, r1, r2 and the divergence angle varied), the ABOP ternary tree
// with tropism (n = 5, branching angle and elasticity varied) and the stochastic bush (n = 5,
// one seed per tree). LOD levels are chosen by the fraction of the branch length they keep.
//
//   build/bin/bench_multires_lod --benchmark_counters_tabular=true   (figures: docs/multires.md)
#include "lsystem/lsystem.hpp"
#include "lsystem/multires_chain.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <memory>
#include <string>

namespace {

using namespace treelobes::lsystem;

struct Tree {
    ModuleString string;
    TurtleOptions turtle;
    MultiresChain chain;
};

std::string example(const std::string& name) { return std::string(TREELOBES_SOURCE_DIR) + "/lsystem/examples/" + name; }

// Deterministic parameter in [lo, hi] for tree i (no RNG state to share between trees).
double vary(std::size_t i, int salt, double lo, double hi) {
    const std::uint64_t x = (i * 0x9e3779b97f4a7c15ULL) ^ (static_cast<std::uint64_t>(salt) * 0xbf58476d1ce4e5b9ULL);
    return lo + (hi - lo) * static_cast<double>((x >> 11) % 1000) / 999.0;
}

Tree make_tree(std::size_t i) {
    ParseOptions parse;
    DeriveOptions derive_options;
    std::string file;
    switch (i % 3) {
        case 0:
            file = "honda_monopodial.lsys";
            parse.defines = {{"r1", vary(i, 1, 0.85, 0.95)}, {"r2", vary(i, 2, 0.55, 0.68)}, {"d", vary(i, 3, 130, 145)}};
            derive_options.steps = 8;
            break;
        case 1:
            file = "abop_ternary_tropism.lsys";
            parse.defines = {{"a", vary(i, 4, 15, 25)}, {"d1", vary(i, 5, 85, 100)}};
            derive_options.steps = 5;
            break;
        default:
            file = "stochastic_bush.lsys";
            derive_options.seed = i;
            break;
    }
    const LSystem system = load_lsystem(example(file), parse);
    Tree tree;
    tree.string = apply_homomorphism(system, derive(system, derive_options));
    tree.turtle = system.turtle;
    tree.turtle.start = {static_cast<double>(i % 50) * 8.0, static_cast<double>(i / 50) * 8.0, 0.0};
    tree.chain = build_multires_chain(tree.string);
    return tree;
}

const std::vector<Tree>& forest(std::size_t count) {
    static std::map<std::size_t, std::unique_ptr<std::vector<Tree>>> cache;
    auto& slot = cache[count];
    if (!slot) {
        slot = std::make_unique<std::vector<Tree>>();
        for (std::size_t i = 0; i < count; ++i) slot->push_back(make_tree(i));
    }
    return *slot;
}

// The coarsest level keeping at least `percent` % of the tree's branch length.
std::size_t lod_for_length(const MultiresChain& chain, int percent) {
    const double target = chain.lod_length.back() * percent / 100.0;
    const auto it = std::lower_bound(chain.lod_length.begin(), chain.lod_length.end(), target - 1e-12);
    return static_cast<std::size_t>(it - chain.lod_length.begin());
}

void report(benchmark::State& state, std::size_t internodes, std::size_t trees) {
    state.counters["trees"] = static_cast<double>(trees);
    state.counters["internodes"] = static_cast<double>(internodes);
    state.counters["forest_per_s"] = benchmark::Counter(1.0, benchmark::Counter::kIsIterationInvariantRate);
}

// LOD extraction: interpret each tree's chain prefix into a TreeGraph.
void BM_ExtractLod(benchmark::State& state) {
    const auto& trees = forest(static_cast<std::size_t>(state.range(0)));
    const int percent = static_cast<int>(state.range(1));
    std::vector<std::size_t> levels;
    for (const Tree& t : trees) levels.push_back(lod_for_length(t.chain, percent));
    std::size_t internodes = 0;
    for (auto _ : state) {
        internodes = 0;
        for (std::size_t i = 0; i < trees.size(); ++i) {
            const TurtleResult lod = extract_lod(trees[i].chain, levels[i], trees[i].turtle);
            internodes += lod.tree.size() - 1;
            benchmark::DoNotOptimize(lod.tree.nodes.data());
        }
    }
    report(state, internodes, trees.size());
}

// Baseline: the full geometry from the original strings.
void BM_FullGeometry(benchmark::State& state) {
    const auto& trees = forest(static_cast<std::size_t>(state.range(0)));
    std::size_t internodes = 0;
    for (auto _ : state) {
        internodes = 0;
        for (const Tree& t : trees) {
            const TurtleResult full = interpret(t.string, t.turtle);
            internodes += full.tree.size() - 1;
            benchmark::DoNotOptimize(full.tree.nodes.data());
        }
    }
    report(state, internodes, trees.size());
}

// One-off preprocessing: tADT and chain of every tree (greedy, branching length).
void BM_BuildChains(benchmark::State& state) {
    const auto& trees = forest(static_cast<std::size_t>(state.range(0)));
    std::size_t entries = 0;
    for (auto _ : state) {
        entries = 0;
        for (const Tree& t : trees) entries += build_multires_chain(t.string).entries.size();
    }
    state.counters["entries"] = static_cast<double>(entries);
    state.counters["trees"] = static_cast<double>(trees.size());
}

BENCHMARK(BM_ExtractLod)->ArgsProduct({{100, 2000}, {25, 50, 90, 100}})->ArgNames({"trees", "length%"})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FullGeometry)->Arg(100)->Arg(2000)->ArgName("trees")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildChains)->Arg(100)->Arg(2000)->ArgName("trees")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
