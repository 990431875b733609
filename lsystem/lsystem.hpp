// Parametric L-systems in the conventions of ABOP / cpfg / L-Py: an axiom, productions with
// numeric parameters, conditions, left/right contexts and probabilities, #define constants, a
// derivation length and a seed; an optional homomorphism (interpretation rules) applied to the
// final string before the turtle reads it. The file format is documented in docs/lsystem.md.
//
//   #define r1 0.9
//   derivation length: 10
//   axiom: A(1,10)
//   A(l,w) : l > 0.1 -> !(w)F(l)[&(45)B(l*0.6,w*0.707)]/(137.5)A(l*r1,w*0.707)
//
// Typical use (the turtle options come from the file's headers):
//   LSystem system = load_lsystem("honda.lsys");
//   ModuleString string = apply_homomorphism(system, derive(system));
//   TurtleResult tree = interpret(string, system.turtle);
//
// Everything is deterministic: stochastic choices and ran()/uniform()/normal() draw from one
// seeded generator in left-to-right order, so (file, steps, seed) always gives the same string.
// derive() and apply_homomorphism() do not modify the LSystem and may run concurrently.
#pragma once

#include "lsystem/expression.hpp"
#include "lsystem/module_string.hpp"
#include "lsystem/turtle.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace treelobes::lsystem {

// A module of a predecessor or context: a symbol and the names bound to its parameters.
struct ModulePattern {
    int symbol = -1;
    std::vector<std::string> formals;
};

struct SuccessorModule {
    int symbol = -1;
    std::vector<detail::Expression> params;
};

// One production `left < predecessor > right : condition -> successor : probability`.
struct Rule {
    int line = 0;                             // in the source file, for messages
    std::vector<ModulePattern> left_context;  // nearest module last
    ModulePattern predecessor;
    std::vector<ModulePattern> right_context;  // nearest module first
    std::optional<detail::Expression> condition;
    std::vector<SuccessorModule> successor;
    double probability = 0.0;      // > 0: stochastic rule (weight among its siblings)
    std::size_t bound_params = 0;  // left, predecessor and right parameters, in order
};

struct LSystem {
    std::string source;  // file name (or "<string>") used in messages
    std::shared_ptr<Alphabet> alphabet = std::make_shared<Alphabet>();
    ModuleString axiom{alphabet};
    std::optional<int> derivation_length;               // `derivation length:`
    std::uint64_t seed = 0;                             // `seed:`
    std::vector<Rule> productions;                      // in file order
    std::vector<Rule> homomorphism;                     // `homomorphism:` / `interpretation:` section
    std::vector<int> ignored;                           // `#ignore:` symbols, skipped when matching contexts
    std::unordered_map<std::string, double> constants;  // #define values (after overrides)
    TurtleOptions turtle;                               // `angle:`, `step:`, `width:`, `tropism:`, ...
};

struct ParseOptions {
    // Overrides of #define values (the CLI's --define NAME=VALUE). Naming a constant the file
    // does not define is an error, so typos do not pass silently.
    std::map<std::string, double> defines;
};

// Throws Error::input(source, "line L, column C: ...") for malformed text, Error::usage for
// overrides of unknown constants.
LSystem parse_lsystem(std::string_view text, const std::string& source = "<string>", const ParseOptions& options = {});
LSystem load_lsystem(const std::filesystem::path& path, const ParseOptions& options = {});

// Guards against exponential growth: derivations stop with Error::input instead of exhausting
// memory or running for hours.
constexpr std::size_t kDefaultMaxModules = 10'000'000;
constexpr int kMaxDerivationLength = 100'000;
// Total modules written over all steps may not exceed this multiple of max_modules.
constexpr std::size_t kWorkFactor = 50;

struct DeriveOptions {
    std::optional<int> steps;                      // overrides `derivation length:`
    std::optional<std::uint64_t> seed;             // overrides `seed:`
    std::size_t max_modules = kDefaultMaxModules;  // per string
};

// Applies the productions `steps` times to the axiom (all modules in parallel, ABOP). In each
// step, rules are tried in file order; the first whose predecessor, contexts and condition match
// is applied. When that rule is stochastic, all stochastic rules matching the module are
// candidates and one is drawn with probability proportional to its weight. Modules without a
// matching rule are copied. `%` removes itself and the rest of its branch (cpfg's cut).
// Built-in names in rules: `step` (1-based number of the step being applied) and `steps`.
ModuleString derive(const LSystem& system, const DeriveOptions& options = {});

// Applies the homomorphism rules once to every module (a copy when there are none).
ModuleString apply_homomorphism(const LSystem& system, const ModuleString& string, const DeriveOptions& options = {});

}  // namespace treelobes::lsystem
