// Module strings of parametric L-systems (ABOP ch. 1.10): a sequence of modules, each a symbol
// with zero or more numeric parameters, e.g. `F(1.5)[+(30)A(2,0.7)]`.
//
// Symbols are interned in an Alphabet shared by every string of one L-system, so rules and the
// turtle compare small integers instead of names. Parameters are stored flat (one vector for the
// whole string): derivations of millions of modules stay a handful of allocations.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace treelobes::lsystem {

// Interned module names. Not thread-safe for intern(); everything else is read-only.
class Alphabet {
public:
    // Every alphabet knows the bracket symbols, so ids of '[' and ']' are fixed.
    Alphabet();
    static constexpr int kPush = 0;  // '['
    static constexpr int kPop = 1;   // ']'

    int intern(std::string_view name);
    int find(std::string_view name) const;  // -1 when unknown
    const std::string& name(int symbol) const { return names_[static_cast<std::size_t>(symbol)]; }
    std::size_t size() const { return names_.size(); }

    // Names longer than one character that are not a letter followed by digits (L-Py's
    // `module Apex`) must be declared so that `AB` can still mean the two modules A and B.
    void declare_long_name(std::string_view name);
    const std::vector<std::string>& long_names() const { return long_names_; }

private:
    std::vector<std::string> names_;
    std::unordered_map<std::string, int> ids_;
    std::vector<std::string> long_names_;  // sorted longest first (longest match wins)
};

class ModuleString {
public:
    explicit ModuleString(std::shared_ptr<Alphabet> alphabet = std::make_shared<Alphabet>());

    std::size_t size() const { return symbols_.size(); }
    bool empty() const { return symbols_.empty(); }
    int symbol(std::size_t i) const { return symbols_[i]; }
    const std::string& name(std::size_t i) const { return alphabet_->name(symbols_[i]); }
    std::span<const double> params(std::size_t i) const { return {params_.data() + offsets_[i], params_.data() + offsets_[i + 1]}; }
    std::size_t param_count(std::size_t i) const { return offsets_[i + 1] - offsets_[i]; }
    // First parameter, or `fallback` when the module has none.
    double param_or(std::size_t i, double fallback) const { return offsets_[i + 1] > offsets_[i] ? params_[offsets_[i]] : fallback; }

    void push_back(int symbol, std::span<const double> params = {});
    void push_back(int symbol, std::initializer_list<double> params) {
        push_back(symbol, std::span<const double>(params.begin(), params.size()));
    }
    // Interns `name` in this string's alphabet.
    void push_back(std::string_view name, std::initializer_list<double> params = {});
    // Appends modules [begin, end) of another string over the same alphabet.
    void append(const ModuleString& other, std::size_t begin, std::size_t end);
    void clear();
    void reserve(std::size_t modules, std::size_t params);
    std::size_t total_params() const { return params_.size(); }

    const Alphabet& alphabet() const { return *alphabet_; }
    Alphabet& alphabet() { return *alphabet_; }
    const std::shared_ptr<Alphabet>& alphabet_ptr() const { return alphabet_; }

    // ABOP notation, e.g. `B(1)[A(0.5)A(0.5)]`; parameters in shortest round-trip form.
    std::string to_string() const { return to_string(0, size()); }
    std::string to_string(std::size_t begin, std::size_t end) const;
    // Number of modules with the given name.
    std::size_t count(std::string_view name) const;

    bool operator==(const ModuleString& other) const;  // same names and parameters

private:
    std::shared_ptr<Alphabet> alphabet_;
    std::vector<int> symbols_;
    std::vector<std::uint32_t> offsets_{0};  // size() + 1 entries into params_
    std::vector<double> params_;
};

// Shortest decimal text that reads back to exactly `value` ("0.5", "1e-07", "3").
std::string format_number(double value);

// Parses a bracketed module string such as `C1[C2[C3][C4]][C5]` or `F(1)[+(90)F(1)]F(2)`.
// Parameters must be numbers here (expressions belong in L-system files). Module names: one
// letter followed by digits (`C12`), a declared long name, or one of `+ - & ^ \ / | [ ] ! $ % ~ '
// { } . @`. Throws Error::input(source, "line L, column C: ...") on malformed text.
ModuleString parse_module_string(std::string_view text, const std::string& source = "<string>",
                                 std::shared_ptr<Alphabet> alphabet = nullptr);

}  // namespace treelobes::lsystem
