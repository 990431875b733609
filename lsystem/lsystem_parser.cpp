// Parser of L-system files (format in docs/lsystem.md). Line oriented: comments are blanked
// first (keeping line and column numbers), then every line is a directive (#define, #ignore,
// #module), a header (`axiom:`, `derivation length:`, ...) or a rule (it contains an arrow).
#include "lsystem/lsystem.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "lsystem/module_lexer.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>

namespace treelobes::lsystem {

namespace {

using detail::Cursor;

std::string_view trim(std::string_view s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return s;
}

bool starts_with_word(std::string_view text, std::string_view word) {
    return text.substr(0, word.size()) == word && (text.size() == word.size() || !detail::is_identifier_char(text[word.size()]));
}

// Replaces /* ... */ and # comments by spaces; `#define`, `#ignore`, `#module` at the start of a
// line are directives, not comments. Throws for an unterminated block comment.
std::string blank_comments(std::string_view text, const std::string& source) {
    std::string out(text);
    std::size_t i = 0;
    int line = 1;
    bool line_start = true;  // only spaces so far on this line
    while (i < out.size()) {
        const char c = out[i];
        if (c == '\n') {
            ++line;
            line_start = true;
            ++i;
            continue;
        }
        if (c == '/' && i + 1 < out.size() && out[i + 1] == '*') {
            const std::size_t end = out.find("*/", i + 2);
            if (end == std::string::npos) throw Error::input(source, "line " + std::to_string(line) + ": '/*' comment is never closed");
            for (std::size_t k = i; k < end + 2; ++k)
                if (out[k] == '\n')
                    ++line;
                else
                    out[k] = ' ';
            i = end + 2;
            continue;
        }
        if (c == '#') {
            const std::string_view rest = std::string_view(out).substr(i + 1);
            const bool directive = line_start && (starts_with_word(rest, "define") || starts_with_word(rest, "ignore") ||
                                                  starts_with_word(rest, "module") || starts_with_word(rest, "include"));
            if (!directive) {
                while (i < out.size() && out[i] != '\n') out[i++] = ' ';
                continue;
            }
        }
        if (!std::isspace(static_cast<unsigned char>(c))) line_start = false;
        ++i;
    }
    return out;
}

// Case-insensitive match of a header keyword (words separated by any spaces) followed by ':'.
// Returns the position after the colon, or npos.
std::size_t match_header(std::string_view line, std::string_view keyword) {
    std::size_t i = 0, k = 0;
    while (k < keyword.size()) {
        if (keyword[k] == ' ') {
            if (i >= line.size() || !std::isspace(static_cast<unsigned char>(line[i]))) return std::string_view::npos;
            while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
            ++k;
            continue;
        }
        if (i >= line.size() || std::tolower(static_cast<unsigned char>(line[i])) != keyword[k]) return std::string_view::npos;
        ++i;
        ++k;
    }
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i < line.size() && line[i] == ':') return i + 1;
    if (i == line.size() && keyword == "endlsystem") return i;
    return std::string_view::npos;
}

// Index of the first character at parenthesis depth 0 for which `at(i)` is true, or npos.
template <typename Predicate>
std::size_t find_top_level(std::string_view text, std::size_t from, Predicate at) {
    int depth = 0;
    for (std::size_t i = from; i < text.size(); ++i) {
        if (text[i] == '(')
            ++depth;
        else if (text[i] == ')')
            --depth;
        else if (depth == 0 && at(i))
            return i;
    }
    return std::string_view::npos;
}

const std::set<std::string>& reserved_names() {
    static const std::set<std::string> names = {"step", "steps", "pi",   "and",   "or",   "not", "sin", "cos",     "tan",
                                                "asin", "acos",  "atan", "atan2", "sqrt", "exp", "log", "abs",     "floor",
                                                "ceil", "round", "sign", "min",   "max",  "pow", "ran", "uniform", "normal"};
    return names;
}

class Parser {
public:
    Parser(const std::string& source, const ParseOptions& options) : options_(options) { system_.source = source; }

    LSystem parse(std::string_view text) {
        const std::string clean = blank_comments(text, system_.source);
        std::size_t start = 0;
        int line = 1;
        while (start <= clean.size() && !ended_) {
            std::size_t end = clean.find('\n', start);
            if (end == std::string::npos) end = clean.size();
            parse_line(std::string_view(clean).substr(start, end - start), line);
            start = end + 1;
            ++line;
        }
        finish();
        return std::move(system_);
    }

private:
    enum class Section { Productions, Homomorphism };

    void parse_line(std::string_view text, int line) {
        if (trim(text).empty()) return;
        Cursor cursor(text, system_.source, line);
        cursor.skip_space();
        const std::size_t indent = cursor.pos();
        const std::string_view body = text.substr(indent);
        if (body.front() == '#') return parse_directive(cursor);
        if (parse_header(cursor, body, indent)) return;
        if (find_arrow(text).first != std::string_view::npos) return parse_rule(text, line);
        cursor.fail("expected a rule 'predecessor -> successor', a header such as 'axiom:' or a #define");
    }

    // ---- directives -------------------------------------------------------------------------
    void parse_directive(Cursor& cursor) {
        cursor.consume('#');
        if (cursor.consume("define")) return parse_define(cursor);
        if (cursor.consume("ignore")) {
            cursor.skip_space();
            cursor.consume(':');
            return parse_ignore(cursor);
        }
        if (cursor.consume("module")) {
            cursor.skip_space();
            cursor.consume(':');
            return parse_module_declaration(cursor);
        }
        cursor.fail("#include is not supported; put everything in one file");
    }

    void parse_define(Cursor& cursor) {
        cursor.skip_space();
        const std::size_t name_pos = cursor.pos();
        const std::string name = read_identifier(cursor, "a constant name after #define");
        if (reserved_names().count(name)) cursor.fail_at(name_pos, "'" + name + "' is a built-in name and cannot be #defined");
        if (system_.constants.count(name)) cursor.fail_at(name_pos, "constant '" + name + "' is defined twice");
        cursor.skip_space();
        if (cursor.at_end()) cursor.fail("expected a value after #define " + name);
        double value = detail::parse_constant_expression(cursor, system_.constants);
        expect_end(cursor, "the value of " + name);
        if (const auto it = options_.defines.find(name); it != options_.defines.end()) {
            value = it->second;  // the file's expression was still checked above
            used_overrides_.insert(name);
        }
        system_.constants[name] = value;
    }

    void parse_ignore(Cursor& cursor) {
        while (detail::at_module_name(cursor)) {
            const std::string name = detail::read_module_name(cursor, *system_.alphabet);
            system_.ignored.push_back(system_.alphabet->intern(name));
            cursor.skip_space();
            cursor.consume(',');
        }
        expect_end(cursor, "the #ignore list (module names without parameters)");
    }

    void parse_module_declaration(Cursor& cursor) {
        for (;;) {
            cursor.skip_space();
            if (cursor.at_end()) break;
            const std::size_t pos = cursor.pos();
            const std::string name = read_identifier(cursor, "a module name");
            if (!std::isalpha(static_cast<unsigned char>(name[0]))) cursor.fail_at(pos, "module names start with a letter");
            system_.alphabet->declare_long_name(name);
            cursor.skip_space();
            cursor.consume(',');
        }
    }

    // ---- headers ----------------------------------------------------------------------------
    bool parse_header(Cursor& cursor, std::string_view body, std::size_t indent) {
        auto value_cursor = [&](std::size_t after) {
            cursor.set_pos(indent + after);
            cursor.skip_space();
            return &cursor;
        };
        std::size_t after;
        if ((after = match_header(body, "endlsystem")) != std::string_view::npos) {
            ended_ = true;
            return true;
        }
        if ((after = match_header(body, "lsystem")) != std::string_view::npos) return true;  // cpfg label
        if ((after = match_header(body, "production")) != std::string_view::npos ||
            (after = match_header(body, "productions")) != std::string_view::npos) {
            section_ = Section::Productions;
            expect_end(*value_cursor(after), "'productions:'");
            return true;
        }
        if ((after = match_header(body, "homomorphism")) != std::string_view::npos ||
            (after = match_header(body, "interpretation")) != std::string_view::npos) {
            section_ = Section::Homomorphism;
            expect_end(*value_cursor(after), "'homomorphism:'");
            return true;
        }
        if ((after = match_header(body, "decomposition")) != std::string_view::npos) cursor.fail("decomposition rules are not supported");
        if ((after = match_header(body, "ignore")) != std::string_view::npos) {
            parse_ignore(*value_cursor(after));
            return true;
        }
        if ((after = match_header(body, "axiom")) != std::string_view::npos) {
            parse_axiom(*value_cursor(after));
            return true;
        }
        if ((after = match_header(body, "derivation length")) != std::string_view::npos) {
            Cursor& c = *value_cursor(after);
            const std::size_t pos = c.pos();
            const double n = constant(c, "the derivation length");
            if (n != std::floor(n) || n < 0 || n > kMaxDerivationLength)
                c.fail_at(pos, "derivation length must be a whole number from 0 to " + std::to_string(kMaxDerivationLength));
            system_.derivation_length = static_cast<int>(n);
            return true;
        }
        if ((after = match_header(body, "seed")) != std::string_view::npos) {
            Cursor& c = *value_cursor(after);
            const std::string_view digits = trim(c.rest());
            std::uint64_t seed = 0;
            const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), seed);
            if (ec != std::errc() || end != digits.data() + digits.size())
                c.fail("seed must be a whole number from 0 to 18446744073709551615");
            system_.seed = seed;
            return true;
        }
        return parse_turtle_header(body, value_cursor);
    }

    template <typename ValueCursor>
    bool parse_turtle_header(std::string_view body, ValueCursor value_cursor) {
        TurtleOptions& t = system_.turtle;
        std::size_t after;
        if ((after = match_header(body, "width factor")) != std::string_view::npos) {
            t.width_factor = non_negative(*value_cursor(after), "width factor");
            return true;
        }
        if ((after = match_header(body, "angle")) != std::string_view::npos) {
            t.angle_deg = constant(*value_cursor(after), "the angle");
            return true;
        }
        if ((after = match_header(body, "step")) != std::string_view::npos) {
            t.step = constant(*value_cursor(after), "the step");
            return true;
        }
        if ((after = match_header(body, "width")) != std::string_view::npos) {
            t.initial_width = non_negative(*value_cursor(after), "width");
            return true;
        }
        if ((after = match_header(body, "elasticity")) != std::string_view::npos) {
            t.elasticity = constant(*value_cursor(after), "the elasticity");
            return true;
        }
        if ((after = match_header(body, "tropism")) != std::string_view::npos) {
            Cursor& c = *value_cursor(after);
            for (int k = 0; k < 3; ++k) {
                if (k > 0) {
                    c.skip_space();
                    if (!c.consume(',')) c.fail("tropism needs three components separated by commas: x, y, z");
                }
                t.tropism[k] = detail::parse_constant_expression(c, system_.constants);
            }
            expect_end(c, "the tropism vector");
            return true;
        }
        return false;
    }

    double constant(Cursor& c, const std::string& what) {
        if (c.at_end()) c.fail("expected a value for " + what);
        const double value = detail::parse_constant_expression(c, system_.constants);
        expect_end(c, what);
        return value;
    }
    double non_negative(Cursor& c, const std::string& what) {
        const std::size_t pos = c.pos();
        const double value = constant(c, what);
        if (value < 0) c.fail_at(pos, what + " must not be negative");
        return value;
    }

    void parse_axiom(Cursor& cursor) {
        const std::vector<std::string> no_formals;
        const std::vector<SuccessorModule> modules = parse_successor(cursor, no_formals, false);
        if (modules.empty()) cursor.fail("the axiom is empty");
        system_.axiom.clear();
        std::vector<double> params;
        for (const auto& m : modules) {
            params.clear();
            for (const auto& e : m.params) params.push_back(e.constant_value());
            system_.axiom.push_back(m.symbol, params);
        }
        has_axiom_ = true;
    }

    // ---- rules ------------------------------------------------------------------------------
    // Returns [start, end) of the arrow (`->`, `-->` or the UTF-8 arrow) at parenthesis depth 0.
    static std::pair<std::size_t, std::size_t> find_arrow(std::string_view text) {
        const std::size_t at = find_top_level(text, 0, [&](std::size_t i) {
            return (text[i] == '-' && i + 1 < text.size() && text[i + 1] == '>') || text.substr(i, 3) == "\xE2\x86\x92";
        });
        if (at == std::string_view::npos) return {at, at};
        if (text[at] != '-') return {at, at + 3};
        // `-->`: a '-' right before `->` belongs to the arrow unless it is the predecessor itself.
        if (at > 0 && text[at - 1] == '-' && !trim(text.substr(0, at - 1)).empty()) return {at - 1, at + 2};
        return {at, at + 2};
    }

    void parse_rule(std::string_view text, int line) {
        Rule rule;
        rule.line = line;
        const auto [arrow, arrow_end] = find_arrow(text);
        const std::string_view left = text.substr(0, arrow);
        const std::size_t colon = find_top_level(left, 0, [&](std::size_t i) { return left[i] == ':'; });
        const std::size_t pred_end = colon == std::string_view::npos ? arrow : colon;

        Cursor pred(text.substr(0, pred_end), system_.source, line);
        std::vector<std::string> formals = parse_predecessor(pred, rule);
        rule.bound_params = formals.size();

        if (colon != std::string_view::npos) {
            Cursor cond(text.substr(colon + 1, arrow - colon - 1), system_.source, line, static_cast<int>(colon) + 2);
            const std::string_view condition = trim(cond.rest());
            if (!condition.empty() && condition != "*") {
                detail::NameScope scope{&formals, &system_.constants, true, true};
                rule.condition = detail::parse_expression(cond, scope);
                expect_end(cond, "the condition");
            }
        }

        const std::string_view right = text.substr(arrow_end);
        const std::size_t prob_colon = find_top_level(right, 0, [&](std::size_t i) { return right[i] == ':'; });
        const std::size_t succ_len = prob_colon == std::string_view::npos ? right.size() : prob_colon;
        Cursor succ(right.substr(0, succ_len), system_.source, line, static_cast<int>(arrow_end) + 1);
        rule.successor = parse_successor(succ, formals, true);

        if (prob_colon != std::string_view::npos) {
            const int column = static_cast<int>(arrow_end + prob_colon) + 2;
            Cursor prob(right.substr(prob_colon + 1), system_.source, line, column);
            prob.skip_space();
            const std::size_t pos = prob.pos();
            rule.probability = constant(prob, "the probability");
            if (!(rule.probability > 0.0)) prob.fail_at(pos, "a rule probability must be greater than 0");
        }
        (section_ == Section::Productions ? system_.productions : system_.homomorphism).push_back(std::move(rule));
    }

    // `left < pred > right`; returns the formal names in binding order (left, pred, right).
    std::vector<std::string> parse_predecessor(Cursor& cursor, Rule& rule) {
        std::vector<ModulePattern> items;
        std::ptrdiff_t less = -1, greater = -1;
        for (;;) {
            cursor.skip_space();
            if (cursor.at_end()) break;
            if (cursor.peek() == '<' || cursor.peek() == '>') {
                auto& marker = cursor.peek() == '<' ? less : greater;
                if (marker >= 0 || (cursor.peek() == '<' && greater >= 0))
                    cursor.fail(std::string("unexpected '") + cursor.peek() + "' in the predecessor");
                marker = static_cast<std::ptrdiff_t>(items.size());
                cursor.get();
                continue;
            }
            const std::size_t pos = cursor.pos();
            const std::string name = detail::read_module_name(cursor, *system_.alphabet);
            if (name == "[" || name == "]") cursor.fail_at(pos, "brackets are not supported in predecessors or contexts");
            ModulePattern pattern;
            pattern.symbol = system_.alphabet->intern(name);
            cursor.skip_space();
            if (cursor.consume('(')) pattern.formals = parse_formals(cursor, name);
            items.push_back(std::move(pattern));
        }
        const std::size_t first = less >= 0 ? static_cast<std::size_t>(less) : 0;
        const std::size_t last = greater >= 0 ? static_cast<std::size_t>(greater) : items.size();
        if (last != first + 1)
            cursor.fail_at(0, items.empty() ? "the rule has no predecessor"
                                            : "the predecessor must be one module; write contexts as 'left < A > right'");
        rule.left_context.assign(items.begin(), items.begin() + static_cast<std::ptrdiff_t>(first));
        rule.predecessor = items[first];
        rule.right_context.assign(items.begin() + static_cast<std::ptrdiff_t>(last), items.end());

        std::vector<std::string> formals;
        for (const auto& item : items)
            for (const auto& f : item.formals) {
                if (std::find(formals.begin(), formals.end(), f) != formals.end())
                    cursor.fail_at(0, "parameter name '" + f + "' is used twice in the predecessor");
                formals.push_back(f);
            }
        return formals;
    }

    std::vector<std::string> parse_formals(Cursor& cursor, const std::string& module) {
        std::vector<std::string> formals;
        for (;;) {
            cursor.skip_space();
            const std::size_t pos = cursor.pos();
            if (!detail::is_identifier_start(cursor.peek()))
                cursor.fail("expected a parameter name in the predecessor " + module + "(...) (a name, not an expression)");
            formals.push_back(read_identifier(cursor, "a parameter name"));
            if (reserved_names().count(formals.back()))
                cursor.fail_at(pos, "'" + formals.back() + "' is a built-in name and cannot be a parameter");
            cursor.skip_space();
            if (cursor.consume(')')) return formals;
            if (!cursor.consume(',')) cursor.fail("expected ',' or ')' after a parameter of " + module);
        }
    }

    // Modules with parameter expressions; `*` alone is cpfg's empty successor.
    std::vector<SuccessorModule> parse_successor(Cursor& cursor, const std::vector<std::string>& formals, bool in_rule) {
        std::vector<SuccessorModule> modules;
        if (trim(cursor.rest()) == "*") return modules;
        detail::NameScope scope{&formals, &system_.constants, in_rule, in_rule};
        for (;;) {
            cursor.skip_space();
            if (cursor.at_end()) break;
            const std::string name = detail::read_module_name(cursor, *system_.alphabet);
            SuccessorModule module;
            module.symbol = system_.alphabet->intern(name);
            cursor.skip_space();
            if (cursor.consume('(')) {
                for (;;) {
                    const std::size_t pos = cursor.pos();
                    module.params.push_back(detail::parse_expression(cursor, scope));
                    if (module.params.back().is_constant() && !std::isfinite(module.params.back().constant_value()))
                        cursor.fail_at(pos, "parameter is not a finite number (division by zero?)");
                    cursor.skip_space();
                    if (cursor.consume(')')) break;
                    if (!cursor.consume(',')) cursor.fail("expected ',' or ')' after a parameter of '" + name + "'");
                }
            }
            modules.push_back(std::move(module));
        }
        return modules;
    }

    // ---- helpers ----------------------------------------------------------------------------
    static std::string read_identifier(Cursor& cursor, const std::string& what) {
        cursor.skip_space();
        if (!detail::is_identifier_start(cursor.peek())) cursor.fail("expected " + what + " but found " + cursor.describe_next());
        const std::size_t start = cursor.pos();
        while (detail::is_identifier_char(cursor.peek())) cursor.get();
        return std::string(cursor.text().substr(start, cursor.pos() - start));
    }
    static void expect_end(Cursor& cursor, const std::string& what) {
        cursor.skip_space();
        if (!cursor.at_end()) cursor.fail("unexpected " + cursor.describe_next() + " after " + what);
    }

    void finish() {
        if (!has_axiom_) throw Error::input(system_.source, "no 'axiom:' line");
        for (const auto& [name, value] : options_.defines)
            if (!used_overrides_.count(name))
                throw Error::usage("--define " + name + ": " + system_.source + " has no '#define " + name + "'");
    }

    const ParseOptions& options_;
    LSystem system_;
    Section section_ = Section::Productions;
    bool has_axiom_ = false;
    bool ended_ = false;
    std::set<std::string> used_overrides_;
};

}  // namespace

LSystem parse_lsystem(std::string_view text, const std::string& source, const ParseOptions& options) {
    return Parser(source, options).parse(text);
}

LSystem load_lsystem(const std::filesystem::path& path, const ParseOptions& options) {
    return parse_lsystem(read_file(path), path.string(), options);
}

}  // namespace treelobes::lsystem
