#include "forestry/tree_pipeline.hpp"

#include "classify/feature_table.hpp"
#include "classify/jointboost.hpp"
#include "core/parallel.hpp"
#include "geometry/trimmed_centre.hpp"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <optional>

namespace treelobes::forestry {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point& mark) {
    const auto now = Clock::now();
    const double s = std::chrono::duration<double>(now - mark).count();
    mark = now;
    return s;
}

std::string tree_name(int id) { return "tree " + std::to_string(id); }

std::vector<double> species_probabilities(const PointCloud& cloud, const TreePipelineOptions& options, const std::string& name) {
    const std::vector<double> values = classify::compute_features(cloud, options.features, name);
    classify::FeatureTable table;
    table.feature_names = classify::feature_names();
    table.add_row(name, values);
    const classify::FeatureTable row = table.select_columns(options.model->feature_names, name);
    return options.model->probabilities(row.row(0));
}

// Where the stem stands: the DBH circle's centre when one was fitted (the stem itself), else the
// segmentation's base when it was found at the stem, else (a base only placed under the treetop)
// the centre of the tree's points without their outer fifth: crowns are seldom centred on their
// top, more often on their stem, and a limb reaching into a gap or left over from a neighbour pulls
// the plain mean off it (synthetic airborne tiles, docs/tile.md: 1.08 m RMS from the true stems
// against 1.21 m for the plain mean and 2.4-3.5 m under the top).
// z is the ground there, from the tree's own points, else the segmentation's.
Eigen::Vector3d stem_position(const TreeInput& tree, const DbhMeasure& dbh) {
    const Eigen::Vector2d xy = dbh.diameter        ? dbh.centre
                               : tree.base_at_stem ? Eigen::Vector2d(tree.base.head<2>())
                                                   : trimmed_centre_xy(tree.points.positions);
    return {xy.x(), xy.y(), ground_under(tree.points.positions, tree.height_above_ground, xy).value_or(tree.base.z())};
}

// Height as foresters measure it: the top above the ground at the stem. On a slope the largest
// height above the terrain under each point would overstate a crown that reaches downhill, and
// the height of the top above the terrain beneath it would understate one whose top leans uphill.
double tree_height(const TreeInput& tree, const Eigen::Vector3d& stem) {
    float top = tree.points.positions.front().z();
    for (const Eigen::Vector3f& p : tree.points.positions) top = std::max(top, p.z());
    return static_cast<double>(top) - stem.z();
}

// The measures that need only the tree's points (everything but the woody volume).
TreeMeasures measure_tree(const TreeInput& tree, const TreePipelineOptions& options) {
    TreeMeasures m;
    m.id = tree.id;
    m.points = tree.points.size();
    m.dbh = measure_dbh(tree.points.positions, tree.height_above_ground, tree.base, options.dbh);
    m.position = stem_position(tree, m.dbh);
    m.height = tree_height(tree, m.position);
    m.crown = measure_crown(tree.points.positions, m.position, options.crown);
    return m;
}

}  // namespace

TreeOutcome process_tree(const TreeInput& tree, const TreePipelineOptions& options, TreeProducts& products) {
    const std::string name = tree_name(tree.id);
    if (tree.points.size() != tree.height_above_ground.size())
        throw Error(ExitCode::Internal, name + ": one height above ground per point expected");
    if (tree.points.empty()) throw Error(ExitCode::Internal, name + ": a tree without points");
    TreeOutcome outcome;
    outcome.id = tree.id;
    outcome.ok = true;
    auto mark = Clock::now();
    if (tree.points.size() < options.min_points) {  // measured only: too few points for a model
        outcome.measures = measure_tree(tree, options);
        outcome.seconds.emplace_back("measures", seconds_since(mark));
        return outcome;
    }

    outcome.measures = measure_tree(tree, options);
    outcome.seconds.emplace_back("measures", seconds_since(mark));

    // An airborne crown's skeleton is joined to the ground at the stem's position.
    ReconstructOptions reconstruct = options.reconstruct;
    reconstruct.hidden_stem_foot = outcome.measures.position.cast<float>();
    reconstruct.warn_if_not_a_tree = false;  // the tile counts them in one line
    // An airborne crown (its base only placed under the treetop) was scanned from above: its
    // sparse steep planes are scan lines, not walls (reconstruct/tree_quality.hpp).
    reconstruct.quality.airborne = !tree.base_at_stem;
    const TreeReconstruction reconstruction = reconstruct_tree(tree.points, reconstruct, name);
    outcome.measures.not_a_tree = reconstruction.summary.quality.not_a_tree;
    outcome.seconds.emplace_back("reconstruct", seconds_since(mark));
    products.skeleton = reconstruction.skeleton;
    products.branches = build_branch_mesh(reconstruction.skeleton, options.mesh);
    outcome.seconds.emplace_back("branch mesh", seconds_since(mark));

    const lobes::LobeTree lobe_tree = lobes::build_lobe_tree(tree.points, reconstruction, reconstruct, {}, options.lobes);
    products.tlobe = lobes::encode_tlobe(lobe_tree, options.tlobe);
    products.lobes = lobe_tree.lobes.size();
    outcome.seconds.emplace_back("lobes", seconds_since(mark));

    const encode::StoredTree stored = encode::store_tree(reconstruction.skeleton, options.dbf6, name);
    products.dbf6 = encode::write_tree_file_bytes(stored);
    outcome.seconds.emplace_back("dbf6", seconds_since(mark));

    outcome.measures.woody_volume = woody_volume(reconstruction.skeleton);

    if (options.model) {
        outcome.measures.species_probabilities = species_probabilities(tree.points, options, name);
        outcome.seconds.emplace_back("species", seconds_since(mark));
    }
    outcome.skeleton = reconstruction.skeleton;
    outcome.modelled = true;
    return outcome;
}

std::vector<TreeOutcome> process_trees(std::span<const TreeInput> trees, const TreePipelineOptions& options, const TreeDone& done) {
    std::vector<TreeOutcome> outcomes(trees.size());
    std::mutex report;
    // Large trees first: the slowest work starts early, so the last thread does not wait alone.
    std::vector<std::size_t> order(trees.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return trees[a].points.size() > trees[b].points.size(); });
    treelobes::parallel_for(std::size_t{0}, order.size(), [&](std::size_t k) {
        const std::size_t i = order[k];
        TreeProducts products;
        TreeOutcome outcome;
        try {
            outcome = process_tree(trees[i], options, products);
        } catch (const Error& e) {
            outcome = {};
            outcome.failure = e.what();
            outcome.failure_code = e.code();
        } catch (const std::exception& e) {  // a bug in one tree must not lose the tile: reported as internal
            outcome = {};
            outcome.failure = std::string("internal error: ") + e.what();
            outcome.failure_code = ExitCode::Internal;
        }
        outcome.id = trees[i].id;
        {
            const std::lock_guard lock(report);
            if (done) done(outcome, outcome.modelled ? &products : nullptr);
        }
        outcomes[i] = std::move(outcome);
    });
    return outcomes;
}

std::vector<int> vote_species(const std::vector<TreeOutcome>& outcomes, const classify::VotingOptions& options) {
    std::vector<std::vector<double>> probabilities;
    std::vector<Eigen::Vector2d> positions;
    std::vector<std::size_t> index;
    for (std::size_t i = 0; i < outcomes.size(); ++i) {
        if (!outcomes[i].ok || outcomes[i].measures.species_probabilities.empty()) continue;
        probabilities.push_back(outcomes[i].measures.species_probabilities);
        positions.push_back(outcomes[i].measures.position.head<2>());
        index.push_back(i);
    }
    std::vector<int> voted(outcomes.size(), -1);
    if (probabilities.empty()) return voted;
    const classify::VotingResult vote = classify::spatial_vote(probabilities, positions, options);
    for (std::size_t k = 0; k < index.size(); ++k) voted[index[k]] = vote.species[k];
    return voted;
}

}  // namespace treelobes::forestry
