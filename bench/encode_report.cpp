// Strnad et al. 2020, §4, Experiment 1 (Tables 3 and 4) and the Fig. 5 error figures for our trees:
//   encode_report [--quick] [SKELETON.ply ...]
// For every tree and r = 3, 5, 10: DBF6 code lengths at LOD 0..3 (thresholds at uniform
// positions of the sorted unique branch thicknesses), the DBF6 length relative to F6 at each LOD, and the
// maximum/average Hausdorff distance of the decoded full-detail skeleton, normalised by the
// bounding-box diagonal, with the √3·d/2 vertex bound checked.
//
// Synthetic trees come from the deterministic generator of tests/encode/random_tree.hpp with
// species-like growth profiles; switch to synth/ (species library) once it lands. Skeleton PLY
// files given on the command line (e.g. reconstructed real trees) are added with l = median edge.
#include "core/error.hpp"
#include "core/skeleton_io.hpp"
#include "encode/chain_code.hpp"
#include "encode/hausdorff.hpp"
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"
#include "tests/encode/random_tree.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

using namespace treelobes;
using namespace treelobes::encode;

namespace {

constexpr double kResolutions[] = {3.0, 5.0, 10.0};
constexpr int kLevels = 4;
constexpr int kTimingRuns = 5;

struct Subject {
    std::string name;
    TreeGraph tree;
    double internode_length = 0.0;  // 0 = median edge
};

std::vector<test::RandomTreeProfile> species_profiles(bool quick) {
    auto profile = [](std::string name, int nodes, int trunk, double wiggle, double fork, int laterals, double angle, double ratio,
                      int order, int stems) {
        test::RandomTreeProfile p;
        p.name = std::move(name);
        p.max_nodes = nodes;
        p.trunk_internodes = trunk;
        p.wiggle_degrees = wiggle;
        p.fork_probability = fork;
        p.max_laterals = laterals;
        p.branch_angle_degrees = angle;
        p.lateral_length_ratio = ratio;
        p.max_order = order;
        p.root_stems = stems;
        p.shuffle = false;
        return p;
    };
    std::vector<test::RandomTreeProfile> profiles = {
            profile("excurrent-whorled", 5000, 80, 2.0, 0.7, 4, 75.0, 0.4, 4, 1),
            profile("decurrent-bifurcating", 5000, 40, 8.0, 0.5, 1, 35.0, 0.9, 7, 1),
            profile("multistem-shrub", 2000, 20, 12.0, 0.5, 2, 40.0, 0.85, 6, 4),
            profile("straight-sparse", 1000, 80, 0.0, 0.25, 1, 50.0, 0.6, 4, 1),
            profile("tortuous", 3000, 35, 25.0, 0.5, 2, 50.0, 0.85, 7, 1),
    };
    if (quick)
        for (auto& p : profiles) p.max_nodes /= 10;
    return profiles;
}

struct Row {
    std::size_t dbf6[kLevels] = {};
    std::size_t f6[kLevels] = {};
    HausdorffResult hausdorff;
    VertexErrorCheck bound;
    double encode_ms = 0.0, decode_ms = 0.0;
};

double milliseconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

Row measure(const Subject& subject, double resolution) {
    EncodeOptions options;
    options.resolution = resolution;
    options.internode_length = subject.internode_length;
    Row row;
    EncodedTree encoded;
    // Timings: the fastest of a few runs, since the machine is shared.
    row.encode_ms = row.decode_ms = 1e300;
    for (int run = 0; run < kTimingRuns; ++run) {
        const auto start = std::chrono::steady_clock::now();
        encoded = encode_tree(subject.tree, options, subject.name);
        row.encode_ms = std::min(row.encode_ms, milliseconds_since(start));
    }
    ChainCode f6 = encoded.code;
    f6.kind = CodeKind::F6;
    f6.symbols = write_symbols(encoded.internodes, CodeKind::F6);
    const std::vector<double> thresholds = lod_thresholds(branch_thicknesses(encoded.code), kLevels);
    const std::vector<ChainCode> dbf6_levels = lod_chain(encoded.code, thresholds);
    const std::vector<ChainCode> f6_levels = lod_chain(f6, thresholds);
    for (int k = 0; k < kLevels; ++k) {
        row.dbf6[k] = dbf6_levels[k].symbols.size();
        row.f6[k] = f6_levels[k].symbols.size();
    }
    TreeGraph decoded;
    for (int run = 0; run < kTimingRuns; ++run) {
        const auto start = std::chrono::steady_clock::now();
        decoded = decode_tree(encoded.code, encoded.geometry);
        row.decode_ms = std::min(row.decode_ms, milliseconds_since(start));
    }
    row.hausdorff = skeleton_hausdorff(subject.tree, decoded);
    row.bound = check_vertex_error(subject.tree, decoded, encoded.decoded_to_source, encoded.geometry.voxel_size);
    return row;
}

// Table 2 columns: internodes, forks, branch levels (Weibull order: +1 per lateral).
void print_properties(const std::vector<Subject>& subjects) {
    std::printf("\nTree properties (cf. Table 2)\n\n| tree | internodes | forks | branch levels |\n|---|---|---|---|\n");
    for (const Subject& s : subjects) {
        EncodeOptions options;
        options.internode_length = s.internode_length;
        const EncodedTree encoded = encode_tree(s.tree, options, s.name);
        const TreeGraph ordered = decode_tree(encoded.code, encoded.geometry);  // main child first
        const auto orders = ordered.branch_orders();
        std::size_t forks = 0;
        for (const auto& node : s.tree.nodes) forks += node.children.size() > 1;
        std::printf("| %s | %zu | %zu | %d |\n", s.name.c_str(), s.tree.size() - 1, forks,
                    *std::max_element(orders.begin(), orders.end()) + 1);
    }
}

void print_tables(const std::vector<Subject>& subjects, const std::vector<std::vector<Row>>& rows) {
    std::printf("\nDBF6 code lengths, LOD0/LOD1/LOD2/LOD3 (cf. Table 3)\n\n| tree | r = 3 | r = 5 | r = 10 |\n|---|---|---|---|\n");
    for (std::size_t t = 0; t < subjects.size(); ++t) {
        std::printf("| %s |", subjects[t].name.c_str());
        for (const Row& row : rows[t]) std::printf(" %zu/%zu/%zu/%zu |", row.dbf6[0], row.dbf6[1], row.dbf6[2], row.dbf6[3]);
        std::printf("\n");
    }
    std::printf(
            "\nReduction of the DBF6 length relative to F6 in %%, LOD0/../LOD3 (cf. Table 4)\n\n"
            "| tree | r = 3 | r = 5 | r = 10 |\n|---|---|---|---|\n");
    for (std::size_t t = 0; t < subjects.size(); ++t) {
        std::printf("| %s |", subjects[t].name.c_str());
        for (const Row& row : rows[t]) {
            for (int k = 0; k < kLevels; ++k)
                std::printf("%s%.0f", k ? "/" : " ", 100.0 * (1.0 - static_cast<double>(row.dbf6[k]) / row.f6[k]));
            std::printf(" |");
        }
        std::printf("\n");
    }
    std::printf(
            "\nDBF6/F6 length ratio at LOD0, normalised Hausdorff max/avg of the decoded skeleton (cf. Fig. 5),\n"
            "largest vertex error / bound √3·d/2, encode and decode time\n\n"
            "| tree | r | DBF6/F6 | Δmax | Δavg | vertex error / bound | encode ms | decode ms |\n"
            "|---|---|---|---|---|---|---|---|\n");
    for (std::size_t t = 0; t < subjects.size(); ++t)
        for (std::size_t i = 0; i < rows[t].size(); ++i) {
            const Row& row = rows[t][i];
            std::printf("| %s | %g | %.3f | %.2e | %.2e | %.3f%s | %.2f | %.2f |\n", subjects[t].name.c_str(), kResolutions[i],
                        static_cast<double>(row.dbf6[0]) / row.f6[0], row.hausdorff.max_normalised, row.hausdorff.mean_normalised,
                        row.bound.max_error / row.bound.bound, row.bound.within_bound ? "" : " EXCEEDED", row.encode_ms, row.decode_ms);
        }
}

}  // namespace

int main(int argc, char** argv) {
    bool quick = false;
    std::vector<std::string> files;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--quick")
            quick = true;
        else if (arg == "--help" || arg == "-h") {
            std::printf("usage: encode_report [--quick] [SKELETON.ply ...]\n");
            return 0;
        } else
            files.push_back(arg);
    }
    try {
        std::vector<Subject> subjects;
        std::uint32_t seed = 1;
        for (const auto& profile : species_profiles(quick))
            subjects.push_back({profile.name, test::random_tree(profile, seed++), profile.internode_length});
        for (const auto& file : files) subjects.push_back({file, read_skeleton_ply(file), 0.0});

        std::vector<std::vector<Row>> rows;
        bool all_within_bound = true;
        for (const Subject& subject : subjects) {
            rows.emplace_back();
            for (double r : kResolutions) {
                rows.back().push_back(measure(subject, r));
                all_within_bound = all_within_bound && rows.back().back().bound.within_bound;
            }
        }
        std::printf("# Chain coding of tree skeletons (Strnad et al. 2020, §4, Experiment 1)\n");
        std::printf("Synthetic trees: tests/encode/random_tree.hpp profiles (seeds 1..%zu), l = 0.1 m, radius unit 1 mm.\n",
                    species_profiles(quick).size());
        print_properties(subjects);
        print_tables(subjects, rows);
        std::printf("\nAll decoded vertices within √3·d/2: %s\n", all_within_bound ? "yes" : "NO");
        return all_within_bound ? 0 : 1;
    } catch (const Error& e) {
        std::fprintf(stderr, "encode_report: %s\n", e.what());
        return static_cast<int>(e.code());
    }
}
