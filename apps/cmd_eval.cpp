// `treelobes eval skeleton --skeleton S.ply --reference R`: distances in both directions,
// length ratio, trunk radius error at breast height, connected pieces and (for tree references with radii)
// branch detection precision/recall. R is a skeleton PLY, a TreeQSM cylinder table or a
// WoodSKE-style point list (reconstruct/skeleton_eval.hpp).
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/version.hpp"
#include "reconstruct/skeleton_eval.hpp"
#include "reconstruct/visible_reference.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <memory>

namespace treelobes::cli {

namespace {

struct EvalSkeletonOptions {
    std::string skeleton;
    std::string reference;
    std::string reference_kind = "auto";
    std::string skeleton_kind = "auto";
    std::string samples_out;
    std::string visible_in;
    std::size_t visible_points = 5;
    EvalOptions eval;
};

nlohmann::json optional_json(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(); }

nlohmann::json stats_json(const DistanceStats& s) {
    return {{"samples", s.samples}, {"mean", s.mean}, {"median", s.median}, {"p95", s.p95}, {"max", s.max}};
}

nlohmann::json to_json(const EvalSkeletonOptions& o, const OptionTable& table, const SkeletonGraph& ref, const SkeletonComparison& c) {
    nlohmann::json j = {{"treelobes", kVersion},
                        {"command", "eval skeleton"},
                        {"options", table.json()},
                        {"skeleton", o.skeleton},
                        {"reference", o.reference},
                        {"reference_kind", ref.kind},
                        {"visible_in", o.visible_in.empty() ? nlohmann::json() : nlohmann::json(o.visible_in)},
                        {"sample_step", o.eval.sample_step},
                        {"skeleton_to_reference", stats_json(c.to_reference)},
                        {"reference_to_skeleton", stats_json(c.from_reference)},
                        {"length", c.length},
                        {"reference_length", optional_json(c.reference_length)},
                        {"length_ratio", optional_json(c.length_ratio)},
                        {"touched_reference_length", optional_json(c.touched_reference_length)},
                        {"breast_height", o.eval.breast_height},
                        {"trunk_radius", optional_json(c.trunk_radius)},
                        {"reference_trunk_radius", optional_json(c.reference_trunk_radius)},
                        {"trunk_radius_error", optional_json(c.trunk_radius_error)},
                        {"components", c.components},
                        {"reference_components", ref.kind == "points" ? nlohmann::json() : nlohmann::json(c.reference_components)}};
    if (c.branches)
        j["branches"] = {{"reference_branches", c.branches->reference_branches},
                         {"detected", c.branches->detected},
                         {"recall", c.branches->recall},
                         {"skeleton_branches", c.branches->skeleton_branches},
                         {"correct", c.branches->correct},
                         {"precision", c.branches->precision}};
    return j;
}

void print_stats(const char* label, const DistanceStats& s) {
    std::printf("  %-24s mean %.4f  median %.4f  p95 %.4f  max %.4f m  (%zu samples)\n", label, s.mean, s.median, s.p95, s.max, s.samples);
}

void print_human(const EvalSkeletonOptions& o, const SkeletonGraph& ref, const SkeletonComparison& c) {
    std::printf(
            "%s vs %s (%s%s)\n", o.skeleton.c_str(), o.reference.c_str(), ref.kind.c_str(),
            o.visible_in.empty() ? "" : ", the part the scan sees: touched for the skeleton's side, by enough points for the reference's");
    print_stats("skeleton -> reference:", c.to_reference);
    print_stats("reference -> skeleton:", c.from_reference);
    std::printf("  length %.2f m", c.length);
    if (c.touched_reference_length && c.reference_length && c.length_ratio)
        std::printf("; reference %.2f m seen well, %.2f m touched by the scan; ratio to the part seen well %.3f", *c.reference_length,
                    *c.touched_reference_length, *c.length_ratio);
    else {
        if (c.reference_length) std::printf(", reference %.2f m", *c.reference_length);
        if (c.length_ratio) std::printf(", ratio %.3f", *c.length_ratio);
    }
    std::printf("\n");
    if (c.trunk_radius && c.reference_trunk_radius)
        std::printf("  trunk radius at %.2f m %.4f m, reference %.4f m, error %+.1f %%\n", o.eval.breast_height, *c.trunk_radius,
                    *c.reference_trunk_radius, c.trunk_radius_error ? 100.0 * *c.trunk_radius_error : 0.0);
    std::printf("  connected components %zu", c.components);
    if (ref.kind != "points") std::printf(" (reference %zu)", c.reference_components);
    std::printf("\n");
    if (c.branches)
        std::printf("  branches: recall %.3f (%zu of %zu thicker than %.3f m), precision %.3f (%zu of %zu)\n", c.branches->recall,
                    c.branches->detected, c.branches->reference_branches, o.eval.min_branch_diameter, c.branches->precision,
                    c.branches->correct, c.branches->skeleton_branches);
}

// Skeleton samples with their distance to the reference, as a point cloud (scalar_distance).
void write_samples(const SkeletonComparison& c, const std::string& path) {
    PointCloud cloud;
    if (!c.sample_positions.empty()) cloud.origin = c.sample_positions.front().array().round().matrix();
    for (const auto& p : c.sample_positions) cloud.positions.push_back((p - cloud.origin).cast<float>());
    auto& distance = cloud.add_extra("distance", AttributeType::Float32);
    distance.values.assign(c.sample_distances.begin(), c.sample_distances.end());
    write_point_cloud(cloud, path);
}

int run_eval_skeleton(const EvalSkeletonOptions& o, const OptionTable& table, const GlobalOptions& global) {
    const SkeletonGraph skeleton = read_skeleton_graph(o.skeleton, o.skeleton_kind);
    const SkeletonGraph reference = read_skeleton_graph(o.reference, o.reference_kind);
    SkeletonComparison c;
    if (o.visible_in.empty()) {
        c = compare_skeletons(skeleton, reference, o.eval);
    } else {
        const PointCloud scan = read_point_cloud(o.visible_in);
        const ExtraAttribute* internode = scan.extra("internode");
        if (!internode)
            throw Error::input(o.visible_in, "--visible-in needs a scan with the `internode` attribute (a `treelobes synth` scan)");
        // Leaf points count too: they carry the internode of the twig they grow on, whose place
        // they show (a skeleton through a leafy twig is right).
        c = compare_with_visible_part(skeleton, reference, internode->values, o.visible_points, o.eval);
    }
    if (!o.samples_out.empty()) write_samples(c, o.samples_out);
    if (global.json)
        std::cout << to_json(o, table, reference, c).dump(2) << "\n";
    else
        print_human(o, reference, c);
    return 0;
}

}  // namespace

void add_eval_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    CLI::App* eval = app.add_subcommand("eval", "Score results against references");
    eval->require_subcommand(1);
    auto options = std::make_shared<EvalSkeletonOptions>();
    CLI::App* sub =
            eval->add_subcommand("skeleton", "Compare a skeleton PLY with a reference skeleton, TreeQSM cylinders or skeleton points");
    auto table = std::make_shared<OptionTable>(sub);
    table->add("--skeleton", options->skeleton, "Skeleton PLY or QSM to score")->required();
    table->add("--reference", options->reference,
               "Skeleton PLY, QSM (TreeQSM cylinder table or SimpleForest/rTwig CSV) or x y z point list")
            ->required();
    table->add("--reference-kind", options->reference_kind, "auto, skeleton, treeqsm or points")
            ->check(CLI::IsMember({"auto", "skeleton", "treeqsm", "points"}));
    table->add("--skeleton-kind", options->skeleton_kind,
               "auto, skeleton (PLY), treeqsm (TreeQSM table or SimpleForest/rTwig CSV) or points: score QSMs and other models too")
            ->check(CLI::IsMember({"auto", "skeleton", "treeqsm", "points"}));
    table->add("--sample-step", options->eval.sample_step, "Metres between samples along segments")->check(cli::PositiveNumber);
    table->add("--match-distance", options->eval.match_distance, "Branch matching tolerance in metres")->check(cli::PositiveNumber);
    table->add("--min-branch-diameter", options->eval.min_branch_diameter,
               "Reference branches thinner than this are not scored, nor the thinner end of a scored one")
            ->check(cli::NonNegativeNumber);
    table->add("--breast-height", options->eval.breast_height,
               "Metres above the reference stem's base at which trunk radii are compared (1.3: where DBH is measured)")
            ->check(cli::NonNegativeNumber);
    table->add("--visible-in", options->visible_in,
               "A synthetic scan of the reference (points labelled with `internode`): score against the part of the "
               "reference it sees, each internode with its way to the root: the skeleton's parts (skeleton -> reference, "
               "precision) against every internode the scan touched, the reference's (reference -> skeleton, recall, length, "
               "trunk) against those holding --visible-points of its points (bark or leaves)");
    table->add("--visible-points", options->visible_points,
               "Scan points an internode needs to count as seen well enough to be expected in the skeleton")
            ->check(CLI::Range(1, 1000000));
    table->add("--samples-out", options->samples_out, "Write the skeleton samples with scalar_distance to this point cloud file");
    sub->callback(
            [options, table, &global, &job] { job = [options, table, &global] { return run_eval_skeleton(*options, *table, global); }; });
}

}  // namespace treelobes::cli
