#include "synth/tile.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/random.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace treelobes::synth {

namespace {

constexpr int kPlacementAttempts = 400;

void check_options(const TileOptions& o) {
    if (o.trees < 0 || o.trees > 100000) throw Error::usage("tile trees must be in [0, 100000]");
    if (!(o.size_m >= 5 && o.size_m <= 2000)) throw Error::usage("tile size must be in [5, 2000] m");
    if (!(o.understory_per_100m2 >= 0 && o.understory_per_100m2 <= 100))
        throw Error::usage("understory density must be in [0, 100] clumps per 100 m^2");
    if (!(o.understory_height_m >= 0.2 && o.understory_height_m <= 5)) throw Error::usage("understory height must be in [0.2, 5] m");
    if (!(o.spacing >= 0 && o.spacing <= 2)) throw Error::usage("tile spacing factor must be in [0, 2]");
}

std::vector<const SpeciesProfile*> chosen_species(const std::vector<SpeciesProfile>& library, const std::vector<std::string>& names) {
    std::vector<const SpeciesProfile*> chosen;
    if (names.empty())
        for (const auto& p : library) chosen.push_back(&p);
    for (const auto& name : names) chosen.push_back(&find_species_profile(library, name));
    if (chosen.empty()) throw Error::usage("the species library is empty");
    return chosen;
}

// Stem footprint (radius at the root collar) and crown radius of a grown tree.
struct Footprint {
    double stem, crown;
};

Footprint footprint(const SyntheticTree& tree) {
    double stem = 0;
    for (std::size_t i = 0; i < tree.skeleton.size(); ++i)
        if (tree.node_level[i] == 0 && tree.skeleton.nodes[i].position.z() < 0.5f)
            stem = std::max(stem, tree.skeleton.nodes[i].position.head<2>().norm() + static_cast<double>(tree.skeleton.nodes[i].radius));
    return {stem, 0.5 * measure(tree).crown_diameter_m};
}

// Dart throwing: the first position far enough from every placed stem. Crowns may touch and
// interlock (spacing < 1), trunks never: the hard limit is the sum of the stem footprints.
bool place(Rng& rng, double size, const Footprint& f, double spacing, const std::vector<Eigen::Vector2d>& at,
           const std::vector<Footprint>& placed, Eigen::Vector2d& out) {
    const double margin = std::min(0.25 * size, std::max(f.stem + 0.5, 0.5 * spacing * f.crown));
    for (int attempt = 0; attempt < kPlacementAttempts; ++attempt) {
        // Drawn last coordinate first, in statements of their own: C++ leaves the order in which function
        // arguments are evaluated to the compiler (GCC right to left, Clang left to right), and this is the
        // order GCC gave the committed outputs.
        const double stem_y = rng.uniform(margin, size - margin);
        const double stem_x = rng.uniform(margin, size - margin);
        const Eigen::Vector2d p(stem_x, stem_y);
        bool free = true;
        for (std::size_t i = 0; i < at.size() && free; ++i) {
            const double hard = f.stem + placed[i].stem + 0.3;
            free = (p - at[i]).norm() >= std::max(hard, spacing * (f.crown + placed[i].crown));
        }
        if (free) {
            out = p;
            return true;
        }
    }
    return false;
}

// Crown competition, after placement. A point of the canopy belongs to the tree whose stem is
// nearest relative to its crown radius (a multiplicatively weighted Voronoi diagram: a broad crown
// claims more ground than a narrow one), among the trees whose top stands above the point, so a
// tall tree's upper crown spreads over a lower neighbour while below that neighbour's top the two
// share the space. A branch node on another tree's ground is cut with all that grows from it;
// trunks are never cut. Ownership uses the crowns as grown alone, so the result does not depend
// on the order in which the trees are pruned.
void compete_for_crown_space(std::vector<PlacedTree>& trees, const std::vector<Footprint>& footprints) {
    constexpr double kMinCrownRadius = 0.5;
    std::vector<double> top(trees.size());
    std::vector<double> radius(trees.size());
    for (std::size_t i = 0; i < trees.size(); ++i) {
        top[i] = trees[i].position.z() + measure(trees[i].tree).height_m;
        radius[i] = std::max(kMinCrownRadius, footprints[i].crown);
    }
    for (std::size_t i = 0; i < trees.size(); ++i) {
        const Eigen::Vector2d stem = trees[i].position.head<2>();
        std::vector<std::size_t> neighbours;
        for (std::size_t j = 0; j < trees.size(); ++j)
            if (j != i && (trees[j].position.head<2>() - stem).norm() < radius[i] + radius[j]) neighbours.push_back(j);
        if (neighbours.empty()) continue;
        SyntheticTree& tree = trees[i].tree;
        prune_subtrees(tree, [&](int node) {
            if (tree.node_level[static_cast<std::size_t>(node)] == 0) return false;
            const Eigen::Vector3d p = trees[i].position + tree.skeleton.nodes[static_cast<std::size_t>(node)].position.cast<double>();
            const double own = (p.head<2>() - stem).norm() / radius[i];
            return std::any_of(neighbours.begin(), neighbours.end(), [&](std::size_t j) {
                return top[j] > p.z() && (p.head<2>() - trees[j].position.head<2>()).norm() / radius[j] < own;
            });
        });
    }
}

TreeTruth truth_row(const PlacedTree& placed, const SpeciesProfile& profile, std::uint64_t seed, const Eigen::Vector3d& origin) {
    const TreeMetrics m = measure(placed.tree);
    TreeTruth truth;
    truth.tree_id = placed.tree_id;
    truth.species = profile.entry.name;
    truth.species_id = profile.entry.id;
    truth.seed = seed;
    truth.base = origin + placed.position;
    truth.height_m = m.height_m;
    truth.dbh_m = m.dbh_m;
    truth.crown_diameter_m = m.crown_diameter_m;
    truth.age_years = placed.tree.age_years;
    return truth;
}

}  // namespace

std::string truth_csv(const std::vector<TreeTruth>& rows) {
    std::string csv = "tree_id,species,species_id,seed,x,y,z,height_m,dbh_m,crown_diameter_m,age_years\n";
    char line[512];
    for (const auto& r : rows) {
        std::snprintf(line, sizeof line, "%d,%s,%d,%llu,%.3f,%.3f,%.3f,%.2f,%.3f,%.2f,%.0f\n", r.tree_id, r.species.c_str(), r.species_id,
                      static_cast<unsigned long long>(r.seed), r.base.x(), r.base.y(), r.base.z(), r.height_m, r.dbh_m, r.crown_diameter_m,
                      r.age_years);
        csv += line;
    }
    return csv;
}

std::uint64_t tree_seed(std::uint64_t seed, std::uint64_t key) { return stream_seed(seed ^ 0x7EEDULL, key); }

Tile make_tile(const std::vector<SpeciesProfile>& library, std::uint64_t seed, const TileOptions& o) {
    check_options(o);
    const std::vector<const SpeciesProfile*> species = chosen_species(library, o.species);
    Rng rng(stream_seed(seed, 0x711E));
    Tile tile;
    tile.scene.origin = o.origin;
    const double aspect = rng.uniform(0, 360);
    tile.scene.ground = make_ground(0, 0, o.size_m, o.size_m, o.slope_deg, aspect, o.roughness_m, stream_seed(seed, 0x6D));

    std::vector<Eigen::Vector2d> stems;
    std::vector<Footprint> footprints;
    std::vector<const SpeciesProfile*> profiles;
    std::vector<std::uint64_t> seeds;
    Progress progress("synth tile: growing trees", static_cast<std::size_t>(o.trees));
    for (int k = 0; k < o.trees; ++k) {
        const SpeciesProfile& profile = *species[rng.below(species.size())];
        const std::uint64_t s = tree_seed(seed, static_cast<std::uint64_t>(k));
        SyntheticTree tree = grow(profile, s, o.grow);
        const Footprint f = footprint(tree);
        Eigen::Vector2d xy;
        // Crowded tiles: let crowns overlap more, but never trunks.
        double spacing = o.spacing;
        while (!place(rng, o.size_m, f, spacing, stems, footprints, xy)) {
            if (spacing == 0)
                throw Error::usage("cannot place " + std::to_string(o.trees) + " trees in a " + std::to_string(o.size_m) +
                                   " m tile without overlapping trunks; use fewer trees or a larger tile");
            spacing = spacing < 0.05 ? 0.0 : 0.7 * spacing;
        }
        stems.push_back(xy);
        footprints.push_back(f);

        PlacedTree placed;
        placed.position = Eigen::Vector3d(xy.x(), xy.y(), tile.scene.ground->height(xy.x(), xy.y()));
        placed.tree_id = k + 1;
        placed.tree = std::move(tree);
        tile.scene.trees.push_back(std::move(placed));
        profiles.push_back(&profile);
        seeds.push_back(s);
        progress.advance();
    }
    progress.finish();
    if (o.competition) compete_for_crown_space(tile.scene.trees, footprints);
    for (std::size_t i = 0; i < tile.scene.trees.size(); ++i)
        tile.truth.push_back(truth_row(tile.scene.trees[i], *profiles[i], seeds[i], o.origin));

    const int clumps = static_cast<int>(std::lround(o.understory_per_100m2 * o.size_m * o.size_m / 100.0));
    double widest = 0;
    for (const auto& f : footprints) widest = std::max(widest, f.stem);
    tile.scene.understory =
            make_understory(*tile.scene.ground, clumps, o.understory_height_m, stream_seed(seed, 0x0B5), stems, widest + 0.3);
    return tile;
}

}  // namespace treelobes::synth
