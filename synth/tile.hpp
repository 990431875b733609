// Synthetic forest tiles: a sloping, rough ground, N trees of mixed species placed without
// trunk overlap, low vegetation, and the truth table that goes with them.
#pragma once

#include "synth/scene.hpp"

#include <string>
#include <vector>

namespace treelobes::synth {

struct TileOptions {
    int trees = 20;
    double size_m = 50;                // square tile side
    std::vector<std::string> species;  // names to mix; empty = every species of the library
    double slope_deg = 4;              // terrain slope; the downhill direction is drawn from the seed
    double roughness_m = 0.25;         // amplitude of the terrain noise
    double understory_per_100m2 = 3;   // bushes/grass clumps per 100 m^2 (0 = none)
    double understory_height_m = 1.2;
    double spacing = 0.4;  // stems at least spacing x (sum of crown radii) apart, relaxed when crowded
    // Neighbours compete for crown space: a branch that grows where a neighbour owns the canopy is
    // cut (crown shyness, the crowns of a closed stand). Off: every tree keeps the crown it grew
    // alone, and the crowns of a crowded tile interpenetrate.
    bool competition = false;
    GrowOptions grow;
    Eigen::Vector3d origin{0, 0, 0};  // added to output coordinates (e.g. a UTM corner)
};

// One row of truth.csv.
struct TreeTruth {
    int tree_id = 0;
    std::string species;
    int species_id = 0;
    std::uint64_t seed = 0;
    Eigen::Vector3d base{0, 0, 0};  // stem base, output coordinates (origin added)
    double height_m = 0, dbh_m = 0, crown_diameter_m = 0, age_years = 0;
};

struct Tile {
    Scene scene;
    std::vector<TreeTruth> truth;  // same order as scene.trees
};

// Throws Error(Usage) for out-of-range options, unknown species, or when the trees cannot be
// placed without overlapping trunks.
Tile make_tile(const std::vector<SpeciesProfile>& library, std::uint64_t seed, const TileOptions& options);

// truth.csv: header `tree_id,species,species_id,seed,x,y,z,height_m,dbh_m,crown_diameter_m,age_years`
// then one row per tree: coordinates to the millimetre, height and crown to the centimetre, DBH
// to the millimetre (metres), age in whole years.
std::string truth_csv(const std::vector<TreeTruth>& rows);

// Seed of tree k of a run seeded with `seed` (tiles, datasets): independent per tree.
std::uint64_t tree_seed(std::uint64_t seed, std::uint64_t key);

}  // namespace treelobes::synth
