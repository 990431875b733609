// tADT and multiresolution chain (Lluch et al. 2010, via Ong's seminar report, §3.1 and §3.3): the report's example and a larger
// hand-checked example with every metric and both orders, LOD prefixes, and exact geometry.
#include "core/error.hpp"
#include "lsystem/lsystem.hpp"
#include "lsystem/multires_chain.hpp"
#include "lsystem_test_util.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace treelobes;
using namespace treelobes::lsystem;
using namespace treelobes::lsystem::test_util;

namespace {

const std::vector<ChainMetric> kMetrics = {ChainMetric::branching_length, ChainMetric::children, ChainMetric::descendants,
                                           ChainMetric::longest_path};

MultiresChain chain_of(const std::string& text, ChainMetric metric, ChainOrder order, TadtOptions tadt = {}) {
    MultiresOptions options;
    options.metric = metric;
    options.order = order;
    options.tadt = std::move(tadt);
    return build_multires_chain(parse_module_string(text), options);
}

// The example of Lluch et al. 2010 (Ong's seminar report, §3.1): five symbols of length 1.
const std::string kSeedExample = "C1[C2[C3][C4]][C5]";
TadtOptions seed_lengths() { return {{"C1", "C2", "C3", "C4", "C5"}, 1.0}; }

// The larger example (docs/lsystem.md draws it). tADT nodes, in creation order, with lengths:
//   0 R F(1): children X (1), Y (6), Z (10)
//   1 X F(2): X1 (2) F(0.5), X2 (3) F(0.6); X2: X2a (4) F(0.3), X2b (5) F(0.4)
//   6 Y F(4) -> 7 F(0.2) -> 8 F(0.1) -> 9 F(0.05)   (a thin chain of single laterals)
//   10 Z F(1.5) (continuation after Y's ']'): Z1 (11) F(0.7) lateral, Z2 (12) F(1.2) continuation
// Branching lengths X 3.8, Y 4.35, Z 3.4; descendants X 5, Y 4, Z 3; longest paths X 3, Y 4, Z 2;
// children X 2, Y 1, Z 2. Every metric puts the branches in another order.
const std::string kLarger = "F(1)[F(2)[F(0.5)][F(0.6)[F(0.3)][F(0.4)]]][F(4)[F(0.2)[F(0.1)[F(0.05)]]]]F(1.5)[F(0.7)]F(1.2)";

}  // namespace

TEST(Tadt, SeedExampleStructureAndLengths) {
    const Tadt t = build_tadt(parse_module_string(kSeedExample), seed_lengths());
    ASSERT_EQ(t.nodes.size(), 5u);
    EXPECT_EQ(t.nodes[0].children, (std::vector<int>{1, 4}));
    EXPECT_EQ(t.nodes[1].children, (std::vector<int>{2, 3}));
    // Total length propagated to the parent at every ']' (walk-through in Ong's seminar report on Lluch et al. 2010, §3.1).
    EXPECT_EQ(t.nodes[0].subtree_length, 5.0);
    EXPECT_EQ(t.nodes[1].subtree_length, 3.0);
    EXPECT_EQ(t.nodes[4].subtree_length, 1.0);
    EXPECT_EQ(t.string.to_string(t.nodes[1].begin, t.nodes[1].end), "C2");
}

TEST(Tadt, ContinuationAfterBracketIsANewNode) {
    const Tadt t = build_tadt(parse_module_string("F(1)+[F(2)]F(3)[F(4)]"));
    ASSERT_EQ(t.nodes.size(), 4u);
    EXPECT_EQ(t.string.to_string(t.nodes[0].begin, t.nodes[0].end), "F(1)+");
    EXPECT_TRUE(t.nodes[1].lateral);
    EXPECT_FALSE(t.nodes[2].lateral);  // F(3) continues the axis after the branch
    EXPECT_EQ(t.nodes[2].parent, 0);
    EXPECT_EQ(t.nodes[3].parent, 2);  // the branch F(4) grows from F(3)
    EXPECT_EQ(t.nodes[0].length, 1.0);
    EXPECT_EQ(t.nodes[0].subtree_length, 10.0);
    EXPECT_THROW(build_tadt(parse_module_string("F]")), Error);
    EXPECT_THROW(build_tadt(parse_module_string("F[")), Error);
}

TEST(Tadt, LargerExampleLengths) {
    const Tadt t = build_tadt(parse_module_string(kLarger));
    ASSERT_EQ(t.nodes.size(), 13u);
    EXPECT_EQ(t.nodes[0].children, (std::vector<int>{1, 6, 10}));
    EXPECT_NEAR(t.nodes[1].subtree_length, 3.8, 1e-12);
    EXPECT_NEAR(t.nodes[6].subtree_length, 4.35, 1e-12);
    EXPECT_NEAR(t.nodes[10].subtree_length, 3.4, 1e-12);
    EXPECT_NEAR(t.nodes[0].subtree_length, 12.55, 1e-12);
    EXPECT_FALSE(t.nodes[10].lateral);
    EXPECT_FALSE(t.nodes[12].lateral);
}

// The report's chain (Ong's seminar report on Lluch et al. 2010, §3.1), for every metric and both orders.
TEST(MultiresChain, SeedExampleExactChain) {
    for (ChainOrder order : {ChainOrder::greedy, ChainOrder::depth_first})
        for (ChainMetric metric : kMetrics) {
            const MultiresChain c = chain_of(kSeedExample, metric, order, seed_lengths());
            EXPECT_EQ(format_chain(c), "C1 SAVE(C1) C2 SAVE(C2) C3 RESTORE(C2) C4 RESTORE(C1) C5")
                    << to_string(metric) << ", " << to_string(order);
            EXPECT_EQ(c.lod_count(), 3u);
            EXPECT_EQ(format_chain(c, ChainLabels::node_id), "C1 SAVE(n0) C2 SAVE(n1) C3 RESTORE(n1) C4 RESTORE(n0) C5");
        }
}

// Hand-checked chains of the larger example. Greedy: after each leaf, the next path starts from
// the root along the highest *remaining* metric.
TEST(MultiresChain, LargerExampleGreedyChains) {
    const auto chain = [](ChainMetric metric) { return format_chain(chain_of(kLarger, metric, ChainOrder::greedy)); };
    // Y (4.35) first; then X (3.8) down to X2b; Z (3.4) beats X's remaining 0.8; then X (0.8 vs
    // Z 0.7) -> X1; Z (0.7 vs X 0.3) -> Z1; finally X2a.
    EXPECT_EQ(chain(ChainMetric::branching_length),
              "F(1) SAVE(F(1)) F(4) F(0.2) F(0.1) F(0.05) RESTORE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.4) "
              "RESTORE(F(1)) F(1.5) SAVE(F(1.5)) F(1.2) RESTORE(F(2)) F(0.5) RESTORE(F(1.5)) F(0.7) RESTORE(F(0.6)) F(0.3)");
    // X (5 nodes) first, X2a on a tie; remaining X 2, Y 4, Z 3 -> Y; Z; X1 (tie with X2, first).
    EXPECT_EQ(chain(ChainMetric::descendants),
              "F(1) SAVE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.3) RESTORE(F(1)) F(4) F(0.2) F(0.1) F(0.05) "
              "RESTORE(F(1)) F(1.5) SAVE(F(1.5)) F(0.7) RESTORE(F(2)) F(0.5) RESTORE(F(0.6)) F(0.4) RESTORE(F(1.5)) F(1.2)");
    // Y (path of 4) first; then X (3) before Z (2).
    EXPECT_EQ(chain(ChainMetric::longest_path),
              "F(1) SAVE(F(1)) F(4) F(0.2) F(0.1) F(0.05) RESTORE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.3) "
              "RESTORE(F(1)) F(1.5) SAVE(F(1.5)) F(0.7) RESTORE(F(2)) F(0.5) RESTORE(F(0.6)) F(0.4) RESTORE(F(1.5)) F(1.2)");
    // X (2 children, tie with Z) first; remaining unvisited children X 1, Y 1, Z 2 -> Z; then X
    // whose X2 (1 unvisited child) beats X1 (none): X2b; X1; Y last (1 child vs Z's 1: Y first).
    EXPECT_EQ(chain(ChainMetric::children),
              "F(1) SAVE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.3) RESTORE(F(1)) F(1.5) SAVE(F(1.5)) F(0.7) "
              "RESTORE(F(0.6)) F(0.4) RESTORE(F(2)) F(0.5) RESTORE(F(1)) F(4) F(0.2) F(0.1) F(0.05) RESTORE(F(1.5)) F(1.2)");
}

// Depth-first: each subtree is finished before the next child of a saved node; the metric only
// orders the children (by their values before any visit).
TEST(MultiresChain, LargerExampleDepthFirstChains) {
    const auto chain = [](ChainMetric metric) { return format_chain(chain_of(kLarger, metric, ChainOrder::depth_first)); };
    EXPECT_EQ(chain(ChainMetric::branching_length),
              "F(1) SAVE(F(1)) F(4) F(0.2) F(0.1) F(0.05) RESTORE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.4) "
              "RESTORE(F(0.6)) F(0.3) RESTORE(F(2)) F(0.5) RESTORE(F(1)) F(1.5) SAVE(F(1.5)) F(1.2) RESTORE(F(1.5)) F(0.7)");
    EXPECT_EQ(chain(ChainMetric::descendants),
              "F(1) SAVE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.3) RESTORE(F(0.6)) F(0.4) RESTORE(F(2)) F(0.5) "
              "RESTORE(F(1)) F(4) F(0.2) F(0.1) F(0.05) RESTORE(F(1)) F(1.5) SAVE(F(1.5)) F(0.7) RESTORE(F(1.5)) F(1.2)");
    EXPECT_EQ(chain(ChainMetric::longest_path),
              "F(1) SAVE(F(1)) F(4) F(0.2) F(0.1) F(0.05) RESTORE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.3) "
              "RESTORE(F(0.6)) F(0.4) RESTORE(F(2)) F(0.5) RESTORE(F(1)) F(1.5) SAVE(F(1.5)) F(0.7) RESTORE(F(1.5)) F(1.2)");
    EXPECT_EQ(chain(ChainMetric::children),
              "F(1) SAVE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.3) RESTORE(F(0.6)) F(0.4) RESTORE(F(2)) F(0.5) "
              "RESTORE(F(1)) F(1.5) SAVE(F(1.5)) F(0.7) RESTORE(F(1.5)) F(1.2) RESTORE(F(1)) F(4) F(0.2) F(0.1) F(0.05)");
}

TEST(MultiresChain, LodIsThePrefixBeforeEachRestore) {
    const MultiresChain c = chain_of(kLarger, ChainMetric::branching_length, ChainOrder::greedy);
    ASSERT_EQ(c.lod_count(), 6u);  // one level per leaf of the tADT
    EXPECT_EQ(format_chain(c, ChainLabels::content, c.lod_end(0)), "F(1) SAVE(F(1)) F(4) F(0.2) F(0.1) F(0.05)");
    EXPECT_EQ(format_chain(c, ChainLabels::content, c.lod_end(1)),
              "F(1) SAVE(F(1)) F(4) F(0.2) F(0.1) F(0.05) RESTORE(F(1)) F(2) SAVE(F(2)) F(0.6) SAVE(F(0.6)) F(0.4)");
    EXPECT_EQ(c.lod_end(5), c.entries.size());
    EXPECT_EQ(c.lod_end(99), c.entries.size());  // clamped
    // Skeletons: LOD 0 is the root and Y's four internodes on one straight line.
    const TurtleResult lod0 = extract_lod(c, 0);
    ASSERT_EQ(lod0.tree.size(), 6u);
    EXPECT_FLOAT_EQ(lod0.tree.nodes.back().position.z(), 1 + 4 + 0.2f + 0.1f + 0.05f);
    EXPECT_EQ(extract_lod(c, 1).tree.size(), 9u);
    EXPECT_EQ(extract_lod(c, 5).tree.size(), 14u);
}

// Interpreting the whole chain gives exactly the original geometry (bit for bit), and every
// prefix is a valid tree contained in it.
TEST(MultiresChain, FullChainReproducesGeometryAndPrefixesAreSubtrees) {
    struct Case {
        std::string name;
        ModuleString string;
        TurtleOptions turtle;
    };
    std::vector<Case> cases;
    for (const char* file : {"honda_monopodial.lsys", "abop_ternary_tropism.lsys", "lluch2010_example.lsys"}) {
        const LSystem s = load_lsystem(example(file));
        cases.push_back({file, apply_homomorphism(s, derive(s)), s.turtle});
    }
    const LSystem bush = load_lsystem(example("stochastic_bush.lsys"));
    for (std::uint64_t seed : {3u, 4u}) cases.push_back({"bush", derive(bush, {4, seed}), bush.turtle});
    // Rotations, widths, leaves, moves and nested empty branches in one string.
    TurtleOptions tropism;
    tropism.elasticity = 0.3;
    tropism.tropism = {0.2, 0, -1};
    cases.push_back({"mixed",
                     parse_module_string("!(0.3)F(1)[&(30)!(0.2)F(0.8)L(0.2)[[^(20)F(0.5)]]/(90)f(0.1)F(0.4)$L]"
                                         "/(137.5)F(1)[+(40)F(2)[-(20)F(1)L]F(0.5)]!F(0.7)[^(35)F(0.3)]F(0.2)L"),
                     tropism});
    for (const Case& c : cases) {
        const TurtleResult original = interpret(c.string, c.turtle);
        const auto full_edges = edges(original.tree);
        for (ChainOrder order : {ChainOrder::greedy, ChainOrder::depth_first})
            for (ChainMetric metric : kMetrics) {
                MultiresOptions options;
                options.metric = metric;
                options.order = order;
                const MultiresChain chain = build_multires_chain(c.string, options);
                const TurtleResult full = extract_lod(chain, chain.lod_count() - 1, c.turtle);
                SCOPED_TRACE(c.name + " " + std::string(to_string(metric)) + " " + std::string(to_string(order)));
                EXPECT_EQ(edges(full.tree), full_edges);
                EXPECT_EQ(leaves(full), leaves(original));
                // Main child first in the chain's tree too: the first child continues the axis.
                for (std::size_t n = 0; n < full.tree.size(); ++n)
                    for (std::size_t k = 1; k < full.tree.nodes[n].children.size(); ++k)
                        EXPECT_NE(full.depth[static_cast<std::size_t>(full.tree.nodes[n].children[k])], full.depth[n]);
                if (metric != ChainMetric::branching_length || order != ChainOrder::greedy) continue;
                // Prefixes: valid trees, growing, each a subset of the full tree. (A level may add
                // no internode: Honda's last laterals hold only an apex, `[&(45)B(l,w)]`.)
                const std::set<Edge> all(full_edges.begin(), full_edges.end());
                std::size_t previous = 1;
                const std::size_t step = std::max<std::size_t>(1, chain.lod_count() / 40);
                for (std::size_t k = 0; k < chain.lod_count(); k += step) {
                    const TurtleResult lod = extract_lod(chain, k, c.turtle);
                    lod.tree.validate("lod");
                    EXPECT_GE(lod.tree.size(), previous);
                    previous = lod.tree.size();
                    EXPECT_NEAR(lod.tree.total_length(), chain.lod_length[k], 1e-4 * (1 + chain.lod_length[k]));
                    for (const Edge& e : edges(lod.tree)) EXPECT_TRUE(all.count(e));
                }
            }
    }
}

// The greedy order adds the branch of largest remaining length first, so its LODs hold more of
// the tree early than the depth-first order, which finishes the top twigs before the big limbs.
TEST(MultiresChain, GreedyRefinesCoarseToFine) {
    const LSystem s = load_lsystem(example("honda_monopodial.lsys"));
    const ModuleString string = derive(s);
    double area[2] = {0, 0};
    for (ChainOrder order : {ChainOrder::greedy, ChainOrder::depth_first}) {
        MultiresOptions options;
        options.order = order;
        const MultiresChain chain = build_multires_chain(string, options);
        ASSERT_EQ(chain.lod_count(), 1024u);
        for (std::size_t k = 0; k < chain.lod_count(); ++k)
            area[order == ChainOrder::greedy ? 0 : 1] += extract_lod(chain, k, s.turtle).tree.total_length();
    }
    EXPECT_GT(area[0], 1.2 * area[1]);
    // Greedy branching length: levels adding length come first, then the 512 apex-only laterals.
    const MultiresChain chain = build_multires_chain(string);
    std::size_t growing = 0;
    for (std::size_t k = 1; k < chain.lod_count(); ++k) {
        const double gain = chain.lod_length[k] - chain.lod_length[k - 1];
        EXPECT_GE(gain, 0.0);
        if (gain > 0) {
            EXPECT_EQ(growing++, k - 1) << "level " << k << " adds length after a level that added none";
        }
    }
    EXPECT_EQ(growing + 1, interpret(string, s.turtle).tree.tip_count());
    EXPECT_NEAR(chain.lod_length.back(), chain.tadt.nodes[0].subtree_length, 1e-9);
}

TEST(MultiresChain, GreedyWorkIsBoundedAndDepthFirstIsLinear) {
    std::string comb;
    for (int i = 0; i < 2000; ++i) comb += "F[F]";
    MultiresOptions options;
    options.max_greedy_work = 10000;
    EXPECT_THROW(build_multires_chain(parse_module_string(comb), options), Error);
    options.order = ChainOrder::depth_first;
    const MultiresChain chain = build_multires_chain(parse_module_string(comb), options);
    EXPECT_EQ(chain.lod_count(), 2000u);  // one level per lateral F
    EXPECT_THROW(build_multires_chain(parse_module_string("F[F"), options), Error);
}

TEST(MultiresChain, NamesOfMetricsAndOrders) {
    for (ChainMetric m : kMetrics) EXPECT_EQ(parse_chain_metric(to_string(m)), m);
    EXPECT_EQ(parse_chain_metric("longest_path"), ChainMetric::longest_path);
    EXPECT_FALSE(parse_chain_metric("length").has_value());
    EXPECT_EQ(parse_chain_order("depth-first"), ChainOrder::depth_first);
    EXPECT_EQ(parse_chain_order("greedy"), ChainOrder::greedy);
}

TEST(MultiresChain, ChainFileListsOneEntryPerLine) {
    const MultiresChain c = chain_of(kSeedExample, ChainMetric::branching_length, ChainOrder::greedy, seed_lengths());
    const std::string text = chain_file_text(c);
    EXPECT_NE(text.find("node 0 root C1\nSAVE 0\nnode 1 lateral C2\nSAVE 1\nnode 2 lateral C3\nRESTORE 1\n"
                        "node 3 lateral C4\nRESTORE 0\nnode 4 lateral C5\n"),
              std::string::npos);
}
