// Trees of the compression experiments (Strnad et al. 2020, §4, Experiments 2 and 3), shared by the report
// program and the Google Benchmark: 12 synthetic trees, one per species of config/species.yaml
// (synth::grow, leafless, seed 1), and a synthetic forest of ~400 trees of all species with
// random heights, positions and orientations. Everything is deterministic.
#pragma once

#include "config/species_library.hpp"
#include "config/species_profile.hpp"
#include "core/random.hpp"
#include "core/tree_graph.hpp"
#include "encode/forest_file.hpp"
#include "synth/grow.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace treelobes::bench {

struct NamedTree {
    std::string name;
    TreeGraph tree;
};

inline std::vector<NamedTree> table5_trees() {
    std::vector<NamedTree> trees;
    synth::GrowOptions options;
    options.leaves = false;
    for (const SpeciesProfile& species : load_species_profiles(default_species_file()))
        trees.push_back({species.entry.name, synth::grow(species, 1, options).skeleton});
    return trees;
}

// A forest of `count` trees on a square plot (20 m per 100 trees): species cycle through the
// library, heights are drawn in the lower 60 % of each species' range, positions uniform,
// orientation a random azimuth (the trees are grown in their own frame and rotated about z when
// placed). Forest trees are young: their crowns have one stem level less than the species' full
// structure (a grown synth tree has ~8,000 internodes on average; the paper's forest of 412
// trees averages 1,792), which gives ~1,700 internodes per tree.
inline std::vector<encode::ForestTree> forest_trees(int count, std::uint64_t seed = 2019) {
    const std::vector<SpeciesProfile> species = load_species_profiles(default_species_file());
    Rng rng(seed);
    const double side = 20.0 * std::sqrt(count / 100.0);
    std::vector<encode::ForestTree> forest;
    for (int i = 0; i < count; ++i) {
        SpeciesProfile profile = species[static_cast<std::size_t>(i) % species.size()];
        if (profile.growth.levels.size() > 2) profile.growth.levels.pop_back();
        synth::GrowOptions options;
        options.leaves = false;
        const auto& h = profile.variation.height_m;
        options.height_m = h.min + (h.max - h.min) * rng.uniform(0.0, 0.6);
        encode::ForestTree tree;
        tree.skeleton = synth::grow(profile, stream_seed(seed, static_cast<std::uint64_t>(i)), options).skeleton;
        tree.skeleton.origin.setZero();
        tree.position = {rng.uniform(0.0, side), rng.uniform(0.0, side), 0.0};
        tree.azimuth = static_cast<float>(rng.uniform(0.0, 2.0 * M_PI));
        tree.name = profile.entry.name + "_" + std::to_string(i);
        forest.push_back(std::move(tree));
    }
    return forest;
}

}  // namespace treelobes::bench
