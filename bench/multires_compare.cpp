// Multiresolution chain (Lluch et al. 2010) against the DBF6 LOD of Strnad et al. 2020 on the same trees: size of the LOD hierarchy and the Hausdorff error of each level against the full tree.
//   bench_multires_compare [--quick]        (prints Markdown; docs/multires_comparison.md holds a run)
//
// Trees: three ABOP L-systems and one real tree (the TreeQSM cylinder model of aRchi's tree1 in
// ../shared/data or $TREELOBES_REAL_DATA, skipped with a note when missing). Every tree is the
// TreeGraph the turtle (or the cylinder table) gives; both methods start from that same graph:
//   multires  tree_to_module_string -> tADT -> greedy branching-length chain; LOD k = prefix
//   DBF6      encode_tree (r = 5, l = median edge, 1 mm radii) -> reduce_lod at thresholds T
// The DBF6 levels use every unique radius as a threshold (a dozen levels at most, evenly spread);
// for each DBF6 level the multires level with the same number of internodes (the smallest with at
// least as many) is compared. Error: symmetric Hausdorff distance between the level's skeleton and
// the full tree, normalised by the tree's bounding-box diagonal (encode/hausdorff.hpp).
#include "core/error.hpp"
#include "encode/chain_code.hpp"
#include "encode/hausdorff.hpp"
#include "encode/lod.hpp"
#include "encode/tree_code.hpp"
#include "lsystem/lsystem.hpp"
#include "lsystem/multires_chain.hpp"
#include "lsystem/tree_string.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace treelobes;
namespace fs = std::filesystem;

namespace {

struct Subject {
    std::string name;
    TreeGraph tree;
};

TreeGraph lsystem_tree(const std::string& file, int steps) {
    const lsystem::LSystem system = lsystem::load_lsystem(std::string(TREELOBES_SOURCE_DIR) + "/lsystem/examples/" + file);
    lsystem::DeriveOptions options;
    options.steps = steps;
    return lsystem::interpret(lsystem::apply_homomorphism(system, lsystem::derive(system, options)), system.turtle).tree;
}

// TreeQSM 2.x cylinder table (radius, length, start xyz, axis xyz, parent, ...; parent 1-based,
// 0 = none): one node per cylinder end, hung from the end of its parent cylinder.
TreeGraph treeqsm_tree(const fs::path& path) {
    std::ifstream in(path);
    if (!in) throw Error::input(path.string(), "cannot open");
    TreeGraph tree;
    std::string line;
    std::vector<int> end_node;
    while (std::getline(in, line)) {
        std::istringstream s(line);
        double radius, length, sx, sy, sz, ax, ay, az;
        int parent;
        if (!(s >> radius >> length >> sx >> sy >> sz >> ax >> ay >> az >> parent)) continue;
        if (tree.empty()) {
            tree.origin = {sx, sy, sz};
            tree.add_node({0, 0, 0}, static_cast<float>(radius), -1);
        }
        const Eigen::Vector3d end = Eigen::Vector3d(sx, sy, sz) + length * Eigen::Vector3d(ax, ay, az) - tree.origin;
        if (parent < 0 || parent > static_cast<int>(end_node.size()))
            throw Error::input(path.string(), "cylinder " + std::to_string(end_node.size() + 1) + " has parent " + std::to_string(parent) +
                                                      " that comes later");
        const int from = parent == 0 ? 0 : end_node[static_cast<std::size_t>(parent - 1)];
        end_node.push_back(tree.add_node(end.cast<float>(), static_cast<float>(radius), from));
    }
    tree.order_children_by_subtree_length();
    tree.validate(path.string());
    return tree;
}

struct Level {
    std::size_t internodes = 0;
    double error = 0.0;  // normalised Hausdorff max
    double mean = 0.0;   // normalised Hausdorff mean
};

Level measure(const TreeGraph& full, const TreeGraph& level) {
    const auto h = encode::skeleton_hausdorff(full, level);
    return {level.size() - 1, h.max_normalised, h.mean_normalised};
}

struct Multires {
    lsystem::TreeString string;
    lsystem::MultiresChain chain;
    std::vector<std::size_t> internodes;  // per LOD

    explicit Multires(const TreeGraph& tree) : string(lsystem::tree_to_module_string(tree)) {
        chain = lsystem::build_multires_chain(string.modules);
        // Internodes per level: count F modules of the visited nodes along the chain.
        const int f = string.modules.alphabet().find("F");
        std::size_t count = 0, lod = 0;
        internodes.assign(chain.lod_count(), 0);
        for (std::size_t e = 0; e < chain.entries.size(); ++e) {
            while (lod < chain.restores.size() && chain.restores[lod] == e) internodes[lod++] = count;
            const auto& entry = chain.entries[e];
            if (entry.kind != lsystem::ChainEntry::Kind::node) continue;
            const auto& node = chain.tadt.nodes[static_cast<std::size_t>(entry.node)];
            for (std::size_t i = node.begin; i < node.end; ++i) count += string.modules.symbol(i) == f;
        }
        internodes.back() = count;
    }
    // The string carries no origin (tree_string.hpp): put the level back in the tree's frame.
    TreeGraph level(std::size_t k, const Eigen::Vector3d& origin) const {
        TreeGraph t = lsystem::extract_lod(chain, k, string.turtle).tree;
        t.origin = origin;
        return t;
    }
    // The coarsest level with at least n internodes.
    std::size_t level_with(std::size_t n) const {
        return static_cast<std::size_t>(std::lower_bound(internodes.begin(), internodes.end(), n) - internodes.begin());
    }
    // Uncompressed bytes: 1 per module symbol, 4 per parameter (float), 4 per chain entry.
    std::size_t bytes() const { return string.modules.size() + 4 * string.modules.total_params() + 4 * chain.entries.size(); }
};

// Thresholds between the unique coded radii, at most `levels` - 1 of them, evenly spread.
std::vector<double> dbf6_thresholds(const std::vector<int>& radii, int levels) {
    std::vector<int> unique = radii;
    std::sort(unique.begin(), unique.end());
    unique.erase(std::unique(unique.begin(), unique.end()), unique.end());
    std::vector<double> t;
    const int n = static_cast<int>(unique.size());
    const int count = std::min(levels - 1, n - 1);
    for (int i = 1; i <= count; ++i) {
        const int index = static_cast<int>(std::lround(static_cast<double>(i) * (n - 1) / (count + 0.0)));
        const double value = unique[static_cast<std::size_t>(std::clamp(index, 1, n - 1))];
        if (t.empty() || value > t.back()) t.push_back(value);
    }
    return t;
}

void compare(const Subject& s, bool quick, std::vector<std::string>& verdicts) {
    const TreeGraph& full = s.tree;
    const Multires multires(full);
    encode::EncodeOptions options;
    options.resolution = 5.0;
    const encode::EncodedTree encoded = encode::encode_tree(full, options, s.name);
    const std::vector<double> thresholds = dbf6_thresholds(encoded.code.radii, quick ? 6 : 12);
    const std::vector<encode::ChainCode> codes = encode::lod_chain(encoded.code, thresholds, s.name);

    // Uncompressed DBF6: 4 bits per symbol (9 symbols), 2 bytes per radius.
    const std::size_t dbf6_bytes = (encoded.code.symbols.size() + 1) / 2 + 2 * encoded.code.radii.size();
    std::printf(
            "\n### %s\n\n%zu internodes, %zu tips, %.2f m of branches. LOD hierarchy: multires %zu levels, chain of "
            "%zu entries, %zu bytes (string + chain, uncompressed); DBF6 %zu levels from one code of %zu symbols + %zu "
            "radii, %zu bytes (uncompressed).\n\n",
            s.name.c_str(), full.size() - 1, full.tip_count(), full.total_length(), multires.chain.lod_count(),
            multires.chain.entries.size(), multires.bytes(), codes.size(), encoded.code.symbols.size(), encoded.code.radii.size(),
            dbf6_bytes);
    std::printf(
            "| DBF6 T (mm) | DBF6 internodes | DBF6 error max / mean | multires LOD | multires internodes | "
            "multires error max / mean | smaller max error |\n|---|---|---|---|---|---|---|\n");
    int multires_wins = 0, dbf6_wins = 0;
    for (std::size_t k = 0; k < codes.size(); ++k) {
        const TreeGraph decoded = encode::decode_tree(codes[k], encoded.geometry, s.name);
        const Level d = measure(full, decoded);
        const std::size_t lod = multires.level_with(d.internodes);
        const Level m = measure(full, multires.level(lod, full.origin));
        const bool m_better = m.error < d.error;
        (m_better ? multires_wins : dbf6_wins) += 1;
        std::printf("| %s | %zu | %.4f / %.5f | %zu | %zu | %.4f / %.5f | %s |\n",
                    k == 0 ? "full" : std::to_string(static_cast<int>(thresholds[k - 1])).c_str(), d.internodes, d.error, d.mean, lod,
                    m.internodes, m.error, m.mean, m_better ? "multires" : "DBF6");
    }
    verdicts.push_back(s.name + ": multires smaller at " + std::to_string(multires_wins) + " of " +
                       std::to_string(multires_wins + dbf6_wins) + " levels");
}

}  // namespace

int main(int argc, char** argv) {
    const bool quick = argc > 1 && std::string(argv[1]) == "--quick";
    try {
        std::vector<Subject> subjects;
        subjects.push_back({"Honda monopodial (ABOP 2.6a, n = 10)", lsystem_tree("honda_monopodial.lsys", quick ? 8 : 10)});
        subjects.push_back({"ternary with tropism (ABOP 2.8a, n = 6)", lsystem_tree("abop_ternary_tropism.lsys", quick ? 4 : 6)});
        subjects.push_back({"leafy ternary, branches (n = 6)", lsystem_tree("leafy_ternary.lsys", quick ? 4 : 6)});
        const char* env = std::getenv("TREELOBES_REAL_DATA");
        const fs::path data = env ? fs::path(env) : fs::path(TREELOBES_SOURCE_DIR) / ".." / "shared" / "data";
        const fs::path qsm = data / "archi" / "tree1_treeqsm_cylinders.txt";
        const bool real = fs::exists(qsm);
        if (real) subjects.push_back({"aRchi tree1, TreeQSM cylinders (real)", treeqsm_tree(qsm)});

        std::printf(
                "## Multiresolution chain vs DBF6 LOD\n\nError: symmetric Hausdorff distance to the full tree / "
                "bounding-box diagonal. DBF6 at r = 5 includes its voxel quantisation (the `full` row).\n");
        if (!real) std::printf("\n(real tree skipped: %s not found)\n", qsm.string().c_str());
        std::vector<std::string> verdicts;
        for (const Subject& s : subjects) compare(s, quick, verdicts);
        std::printf("\n### Summary\n\n");
        for (const auto& v : verdicts) std::printf("- %s\n", v.c_str());
        return 0;
    } catch (const Error& e) {
        std::fprintf(stderr, "bench_multires_compare: %s\n", e.what());
        return static_cast<int>(e.code());
    }
}
