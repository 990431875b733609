// Parallel rewriting of module strings (ABOP ch. 1): every module of the current string is
// replaced at once by the successor of the rule that matches it.
#include "core/error.hpp"
#include "lsystem/lsystem.hpp"

#include <cmath>

namespace treelobes::lsystem {

namespace {

class Rewriter {
public:
    Rewriter(const LSystem& system, const std::vector<Rule>& rules) : system_(system), rules_(rules) {
        by_symbol_.resize(system.alphabet->size());
        for (std::size_t r = 0; r < rules.size(); ++r) {
            by_symbol_[static_cast<std::size_t>(rules[r].predecessor.symbol)].push_back(static_cast<int>(r));
            if (!rules[r].left_context.empty() || !rules[r].right_context.empty()) needs_brackets_ = true;
        }
        ignored_.assign(system.alphabet->size(), 0);
        for (int s : system.ignored) ignored_[static_cast<std::size_t>(s)] = 1;
    }

    // Rewrites `in` into `out` (cleared first). Throws when out would exceed max_modules.
    void rewrite(const ModuleString& in, ModuleString& out, int step, int steps, Rng& random, std::size_t max_modules) {
        out.clear();
        if (needs_brackets_) match_brackets(in);
        context_.step = step;
        context_.steps = steps;
        context_.random = &random;
        for (std::size_t i = 0; i < in.size(); ++i) {
            const int rule = select(in, i, random);
            if (rule < 0)
                out.push_back(in.symbol(i), in.params(i));
            else
                produce(rules_[static_cast<std::size_t>(rule)], in, i, out);
            if (out.size() > max_modules)
                throw Error::input(system_.source, "derivation step " + std::to_string(step) + " produces more than " +
                                                           std::to_string(max_modules) +
                                                           " modules; lower the derivation length (--steps) or raise --max-modules");
        }
    }

private:
    bool has_rules(int symbol) const {
        return static_cast<std::size_t>(symbol) < by_symbol_.size() && !by_symbol_[static_cast<std::size_t>(symbol)].empty();
    }

    // The rule to apply to module i, or -1 (copy the module).
    int select(const ModuleString& in, std::size_t i, Rng& random) {
        if (!has_rules(in.symbol(i))) return -1;
        const auto& candidates = by_symbol_[static_cast<std::size_t>(in.symbol(i))];
        for (std::size_t k = 0; k < candidates.size(); ++k) {
            const Rule& rule = rules_[static_cast<std::size_t>(candidates[k])];
            if (!applies(rule, in, i)) continue;
            if (rule.probability <= 0.0) return candidates[k];
            return draw_stochastic(in, i, candidates, k, random);
        }
        return -1;
    }

    // All stochastic rules from position `first` on that match compete, weighted by probability.
    int draw_stochastic(const ModuleString& in, std::size_t i, const std::vector<int>& candidates, std::size_t first, Rng& random) {
        group_.clear();
        double total = 0.0;
        for (std::size_t k = first; k < candidates.size(); ++k) {
            const Rule& rule = rules_[static_cast<std::size_t>(candidates[k])];
            if (rule.probability <= 0.0) continue;
            if (k != first && !applies(rule, in, i)) continue;
            group_.push_back(candidates[k]);
            total += rule.probability;
        }
        double u = random.uniform() * total;
        for (int r : group_) {
            u -= rules_[static_cast<std::size_t>(r)].probability;
            if (u < 0.0) return r;
        }
        return group_.back();  // u == total after rounding
    }

    // Predecessor arity, contexts and condition; leaves the bound parameters in bound_.
    bool applies(const Rule& rule, const ModuleString& in, std::size_t i) {
        bound_.clear();
        if (!bind_left(rule, in, i)) return false;
        if (in.param_count(i) != rule.predecessor.formals.size()) return false;
        const auto p = in.params(i);
        bound_.insert(bound_.end(), p.begin(), p.end());
        if (!bind_right(rule, in, i)) return false;
        if (!rule.condition) return true;
        context_.params = bound_;
        return rule.condition->evaluate(context_) != 0.0;
    }

    // Left context: walk toward the root, skipping ignored modules and whole lateral branches
    // `[...]`, and stepping out of the current branch through its '['.
    bool bind_left(const Rule& rule, const ModuleString& in, std::size_t i) {
        if (rule.left_context.empty()) return true;
        std::ptrdiff_t j = static_cast<std::ptrdiff_t>(i);
        left_found_.clear();
        for (std::size_t k = rule.left_context.size(); k-- > 0;) {
            j = previous(in, j);
            if (j < 0 || !same_module(rule.left_context[k], in, static_cast<std::size_t>(j))) return false;
            left_found_.push_back(static_cast<std::size_t>(j));
        }
        for (auto it = left_found_.rbegin(); it != left_found_.rend(); ++it) {
            const auto p = in.params(*it);
            bound_.insert(bound_.end(), p.begin(), p.end());
        }
        return true;
    }
    std::ptrdiff_t previous(const ModuleString& in, std::ptrdiff_t j) const {
        while (--j >= 0) {
            const int s = in.symbol(static_cast<std::size_t>(j));
            if (s == Alphabet::kPop) {
                j = brackets_[static_cast<std::size_t>(j)];  // at its '['; the loop steps before it
                if (j < 0) return -1;
            } else if (s != Alphabet::kPush && !is_ignored(s)) {
                return j;
            }
        }
        return -1;
    }

    // Right context: walk toward the tips, skipping ignored modules and lateral branches; the end
    // of the current branch (']') ends the search.
    bool bind_right(const Rule& rule, const ModuleString& in, std::size_t i) {
        std::ptrdiff_t j = static_cast<std::ptrdiff_t>(i);
        for (const auto& pattern : rule.right_context) {
            j = next(in, j);
            if (j < 0 || !same_module(pattern, in, static_cast<std::size_t>(j))) return false;
            const auto p = in.params(static_cast<std::size_t>(j));
            bound_.insert(bound_.end(), p.begin(), p.end());
        }
        return true;
    }
    std::ptrdiff_t next(const ModuleString& in, std::ptrdiff_t j) const {
        const auto n = static_cast<std::ptrdiff_t>(in.size());
        while (++j < n) {
            const int s = in.symbol(static_cast<std::size_t>(j));
            if (s == Alphabet::kPush) {
                j = brackets_[static_cast<std::size_t>(j)];  // at its ']'; the loop steps past it
                if (j < 0) return -1;
            } else if (s == Alphabet::kPop) {
                return -1;
            } else if (!is_ignored(s)) {
                return j;
            }
        }
        return -1;
    }

    bool is_ignored(int symbol) const {
        return static_cast<std::size_t>(symbol) < ignored_.size() && ignored_[static_cast<std::size_t>(symbol)];
    }

    static bool same_module(const ModulePattern& pattern, const ModuleString& in, std::size_t j) {
        return in.symbol(j) == pattern.symbol && in.param_count(j) == pattern.formals.size();
    }

    void match_brackets(const ModuleString& in) {
        brackets_.assign(in.size(), -1);
        open_.clear();
        for (std::size_t i = 0; i < in.size(); ++i) {
            if (in.symbol(i) == Alphabet::kPush)
                open_.push_back(i);
            else if (in.symbol(i) == Alphabet::kPop && !open_.empty()) {
                brackets_[i] = static_cast<std::ptrdiff_t>(open_.back());
                brackets_[open_.back()] = static_cast<std::ptrdiff_t>(i);
                open_.pop_back();
            }
        }
    }

    void produce(const Rule& rule, const ModuleString& in, std::size_t i, ModuleString& out) {
        // applies() of the chosen rule may not have been the last call: bind its parameters again
        // (binding draws no random numbers, so the stream is unaffected).
        bound_.clear();
        bind_left(rule, in, i);
        const auto p = in.params(i);
        bound_.insert(bound_.end(), p.begin(), p.end());
        bind_right(rule, in, i);
        context_.params = bound_;
        for (const SuccessorModule& module : rule.successor) {
            values_.clear();
            for (const auto& e : module.params) {
                const double v = e.evaluate(context_);
                if (!std::isfinite(v))
                    throw Error::input(system_.source, "line " + std::to_string(rule.line) + ": the rule gives module '" +
                                                               system_.alphabet->name(module.symbol) + "' a non-finite parameter at step " +
                                                               std::to_string(static_cast<int>(context_.step)) +
                                                               " (division by zero or overflow?)");
                values_.push_back(v);
            }
            out.push_back(module.symbol, values_);
        }
    }

    const LSystem& system_;
    const std::vector<Rule>& rules_;
    std::vector<std::vector<int>> by_symbol_;
    std::vector<char> ignored_;
    bool needs_brackets_ = false;
    std::vector<std::ptrdiff_t> brackets_;
    std::vector<std::size_t> open_, left_found_;
    std::vector<double> bound_, values_;
    std::vector<int> group_;
    detail::EvalContext context_;
};

// cpfg's cut: `%` removes itself and everything after it up to the end of its branch.
void apply_cuts(ModuleString& string) {
    const int cut = string.alphabet().find("%");
    if (cut < 0) return;
    ModuleString out(string.alphabet_ptr());
    out.reserve(string.size(), string.total_params());
    for (std::size_t i = 0; i < string.size(); ++i) {
        if (string.symbol(i) != cut) {
            out.push_back(string.symbol(i), string.params(i));
            continue;
        }
        int depth = 0;
        for (++i; i < string.size(); ++i) {
            const int s = string.symbol(i);
            if (s == Alphabet::kPush)
                ++depth;
            else if (s == Alphabet::kPop && depth-- == 0)
                break;
        }
        if (i < string.size()) out.push_back(string.symbol(i), string.params(i));  // the branch's ']'
    }
    string = std::move(out);
}

}  // namespace

ModuleString derive(const LSystem& system, const DeriveOptions& options) {
    const std::optional<int> steps = options.steps ? options.steps : system.derivation_length;
    if (!steps) throw Error::input(system.source, "no 'derivation length:' line (or give the number of steps)");
    if (*steps < 0 || *steps > kMaxDerivationLength)
        throw Error::usage("derivation length " + std::to_string(*steps) + " is outside 0.." + std::to_string(kMaxDerivationLength));
    if (system.axiom.size() > options.max_modules)
        throw Error::input(system.source, "the axiom has more than " + std::to_string(options.max_modules) + " modules");
    Rng random(options.seed.value_or(system.seed));
    Rewriter rewriter(system, system.productions);
    ModuleString current = system.axiom, next(system.alphabet);
    std::size_t work = 0;
    const std::size_t max_work = kWorkFactor * options.max_modules;
    for (int step = 1; step <= *steps; ++step) {
        rewriter.rewrite(current, next, step, *steps, random, options.max_modules);
        apply_cuts(next);
        std::swap(current, next);
        work += current.size();
        if (work > max_work && step < *steps)
            throw Error::input(system.source, "derivation stopped at step " + std::to_string(step) + " of " + std::to_string(*steps) +
                                                      ": more than " + std::to_string(max_work) +
                                                      " modules rewritten in total; lower the derivation length (--steps)");
    }
    return current;
}

ModuleString apply_homomorphism(const LSystem& system, const ModuleString& string, const DeriveOptions& options) {
    if (system.homomorphism.empty()) return string;
    const int steps = options.steps.value_or(system.derivation_length.value_or(0));
    // An independent stream: adding a stochastic homomorphism does not change the derivation.
    Rng random(options.seed.value_or(system.seed) ^ 0x6a09e667f3bcc909ULL);
    Rewriter rewriter(system, system.homomorphism);
    ModuleString out(system.alphabet);
    rewriter.rewrite(string, out, steps, steps, random, options.max_modules);
    return out;
}

}  // namespace treelobes::lsystem
