// Derivation: the seed-003 sequence, classic ABOP models with known counts, conditions,
// contexts, stochastic rules, cuts, homomorphisms and the guards against runaway growth.
#include "core/error.hpp"
#include "lsystem/lsystem.hpp"
#include "lsystem_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace treelobes;
using namespace treelobes::lsystem;
using treelobes::lsystem::test_util::example;

namespace {

std::string derive_text(const LSystem& system, int steps, std::optional<std::uint64_t> seed = std::nullopt) {
    DeriveOptions options;
    options.steps = steps;
    options.seed = seed;
    return derive(system, options).to_string();
}

std::size_t count_after(const LSystem& system, int steps, const std::string& name) {
    DeriveOptions options;
    options.steps = steps;
    return derive(system, options).count(name);
}

}  // namespace

// Lluch et al. 2010, via Ong's seminar report, §2.1: A(l) : itNum < maxIt -> B(l)[A(l/2)A(l/2)], A(l) : itNum = maxIt -> B(l).
TEST(Derive, Seed003ExampleSequence) {
    const LSystem s = load_lsystem(example("lluch2010_example.lsys"));
    ASSERT_EQ(s.derivation_length, 3);
    // itNum is the number of the step being applied; with maxIt = 3 steps 1-2 use rule 1.
    EXPECT_EQ(derive_text(s, 0), "A(1)");
    EXPECT_EQ(derive_text(s, 1), "B(1)[A(0.5)A(0.5)]");
    EXPECT_EQ(derive_text(s, 2), "B(1)[B(0.5)[A(0.25)A(0.25)]B(0.5)[A(0.25)A(0.25)]]");
    EXPECT_EQ(derive_text(s, 3), "B(1)[B(0.5)[B(0.25)B(0.25)]B(0.5)[B(0.25)B(0.25)]]");
    // The homomorphism draws B(l) as F(l).
    EXPECT_EQ(apply_homomorphism(s, derive(s)).to_string(), "F(1)[F(0.5)[F(0.25)F(0.25)]F(0.5)[F(0.25)F(0.25)]]");
}

// Honda's monopodial tree: every apex makes one internode and two apices -> 2^n - 1 internodes.
TEST(Derive, HondaInternodeCounts) {
    const LSystem s = load_lsystem(example("honda_monopodial.lsys"));
    for (int n = 0; n <= 10; ++n) {
        EXPECT_EQ(count_after(s, n, "F"), (std::size_t{1} << n) - 1) << "n = " << n;
        // Apices A (one: the trunk), B and C together: 2^n.
        EXPECT_EQ(count_after(s, n, "A"), 1u);
        EXPECT_EQ(count_after(s, n, "B") + count_after(s, n, "C") + 1, std::size_t{1} << n);
    }
}

// ABOP Fig. 2.8a: each A makes four internodes and three apices -> 2*3^n - 1 internodes.
TEST(Derive, TernaryTreeInternodeCounts) {
    const LSystem s = load_lsystem(example("abop_ternary_tropism.lsys"));
    int power = 1;
    for (int n = 0; n <= 6; ++n, power *= 3) {
        EXPECT_EQ(count_after(s, n, "F"), static_cast<std::size_t>(2 * power - 1)) << "n = " << n;
        EXPECT_EQ(count_after(s, n, "A"), static_cast<std::size_t>(power));
    }
    // Internodes elongate (F(l) -> F(l*lr)) and widths grow (!(w) -> !(w*vr)) in every step.
    DeriveOptions two;
    two.steps = 2;
    const ModuleString d = derive(s, two);
    EXPECT_DOUBLE_EQ(d.params(1)[0], 200 * 0.01 * 1.109 * 1.109);  // F of the axiom
    EXPECT_DOUBLE_EQ(d.params(0)[0], 0.01 * 1.732 * 1.732);        // !( ) of the axiom
}

TEST(Derive, ConditionsUseParametersStepAndConstants) {
    const LSystem s = parse_lsystem(R"(#define limit 0.3
axiom: A(1)
A(l) : l > limit && step < 4 -> F(l)A(l/2)
A(l) : l <= limit -> L(step, steps)
)");
    EXPECT_EQ(derive_text(s, 1), "F(1)A(0.5)");
    EXPECT_EQ(derive_text(s, 2), "F(1)F(0.5)A(0.25)");
    EXPECT_EQ(derive_text(s, 3), "F(1)F(0.5)L(3,3)");
    EXPECT_EQ(derive_text(s, 5), "F(1)F(0.5)L(3,5)");  // L has no rule: copied
}

TEST(Derive, FirstMatchingRuleWinsAndArityMustMatch) {
    const LSystem s = parse_lsystem("axiom: A(1) A A(1,2)\nA(x) -> B\nA(x) -> C\nA -> D\n");
    EXPECT_EQ(derive_text(s, 1), "BDA(1,2)");
}

// ABOP §1.8: a signal propagates along a filament through left contexts; `#ignore` skips modules.
TEST(Derive, ContextSensitiveSignal) {
    const LSystem s = parse_lsystem("#ignore: +\naxiom: B A + A A\nB < A -> B\nB -> A\n");
    EXPECT_EQ(derive_text(s, 1), "AB+AA");
    EXPECT_EQ(derive_text(s, 2), "AA+BA");
    EXPECT_EQ(derive_text(s, 3), "AA+AB");
    // Parameters of contexts are bound too, in order left, predecessor, right.
    const LSystem p = parse_lsystem("axiom: X(2) A(3) Y(5)\nX(a) < A(b) > Y(c) -> R(a, b, c)\n");
    EXPECT_EQ(derive_text(p, 1), "X(2)R(2,3,5)Y(5)");
}

// Contexts follow the branching: the left context of a branch's first module is the module
// before the '[', lateral branches are skipped, and ']' ends the right context.
TEST(Derive, ContextsFollowBranches) {
    const LSystem s = parse_lsystem(R"(axiom: A[B]C[D]
A < B -> b
A < C -> c
A > C -> a
C > D -> x
B > C -> y
)");
    EXPECT_EQ(derive_text(s, 1), "a[b]c[D]");
}

TEST(Derive, StochasticRulesAreSeededAndDeterministic) {
    const LSystem s = load_lsystem(example("stochastic_bush.lsys"));
    const std::string first = derive_text(s, 5, 7);
    EXPECT_EQ(derive_text(s, 5, 7), first);  // same seed, same plant
    int different = 0;
    for (std::uint64_t seed = 8; seed < 12; ++seed) different += derive_text(s, 5, seed) != first;
    EXPECT_GE(different, 3);
    EXPECT_EQ(derive_text(s, 5), derive_text(s, 5, 1));  // the file's `seed: 1`
}

// With weights 1 : 3, a quarter of 8192 modules takes the first successor (deterministic for the
// seed; the bound is 5 standard deviations).
TEST(Derive, StochasticProbabilitiesAreRespected) {
    const LSystem s = parse_lsystem(R"(derivation length: 14
axiom: X(13)
X(n) : n > 0 -> X(n-1) X(n-1)
X(n) : n == 0 -> Y : 1
X(n) : n == 0 -> Z : 3
)");
    const ModuleString d = derive(s);
    ASSERT_EQ(d.size(), 8192u);
    const double y = static_cast<double>(d.count("Y"));
    EXPECT_EQ(d.count("Y") + d.count("Z"), 8192u);
    EXPECT_NEAR(y, 2048.0, 5 * std::sqrt(8192 * 0.25 * 0.75));
}

TEST(Derive, RandomFunctionsAreSeeded) {
    const LSystem s = parse_lsystem("axiom: A\nA -> F(uniform(1, 2)) F(ran(1)) F(normal(0, 1))\n");
    const ModuleString a = derive(s, {1, 3}), b = derive(s, {1, 3}), c = derive(s, {1, 4});
    EXPECT_TRUE(a == b);
    EXPECT_FALSE(a == c);
    EXPECT_GE(a.params(0)[0], 1.0);
    EXPECT_LT(a.params(0)[0], 2.0);
}

TEST(Derive, CutRemovesTheRestOfTheBranch) {
    const LSystem s = parse_lsystem("axiom: F[X F F[F]]F X F\nX -> %\n");
    EXPECT_EQ(derive_text(s, 1), "F[]F");
}

TEST(Derive, GuardsAgainstExplosiveGrowth) {
    const LSystem s = parse_lsystem("axiom: A\nA -> AA\n");
    DeriveOptions options;
    options.steps = 40;  // 2^40 modules
    options.max_modules = 1000;
    try {
        derive(s, options);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_EQ(std::string(e.what()),
                  "<string>: derivation step 10 produces more than 1000 modules; lower the derivation length (--steps) or "
                  "raise --max-modules");
    }
    // Linear growth over very many steps: bounded by the total work.
    const LSystem slow = parse_lsystem("axiom: A\nA -> FA\n");
    options.steps = 100000;
    EXPECT_THROW(derive(slow, options), Error);
    options.steps = 100001;
    EXPECT_THROW(derive(slow, options), Error);
}

TEST(Derive, NonFiniteParametersAreErrors) {
    const LSystem s = parse_lsystem("axiom: A(0)\n\nA(x) -> A(1/x)\n", "inv.lsys");
    try {
        derive(s, {1, std::nullopt});
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()),
                  "inv.lsys: line 3: the rule gives module 'A' a non-finite parameter at step 1 (division by zero or overflow?)");
    }
    const LSystem no_length = parse_lsystem("axiom: A\n", "n.lsys");
    EXPECT_THROW(derive(no_length), Error);
}
