#include "lsystem/module_string.hpp"

#include "core/error.hpp"
#include "lsystem/expression.hpp"
#include "lsystem/module_lexer.hpp"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <limits>

namespace treelobes::lsystem {

Alphabet::Alphabet() {
    intern("[");
    intern("]");
    declare_long_name("SetHead");  // the one built-in long turtle command (L-Py)
}

int Alphabet::intern(std::string_view name) {
    const auto it = ids_.find(std::string(name));
    if (it != ids_.end()) return it->second;
    const int id = static_cast<int>(names_.size());
    names_.emplace_back(name);
    ids_.emplace(names_.back(), id);
    return id;
}

int Alphabet::find(std::string_view name) const {
    const auto it = ids_.find(std::string(name));
    return it == ids_.end() ? -1 : it->second;
}

void Alphabet::declare_long_name(std::string_view name) {
    if (std::find(long_names_.begin(), long_names_.end(), name) != long_names_.end()) return;
    long_names_.emplace_back(name);
    std::stable_sort(long_names_.begin(), long_names_.end(),
                     [](const std::string& a, const std::string& b) { return a.size() > b.size(); });
}

ModuleString::ModuleString(std::shared_ptr<Alphabet> alphabet) : alphabet_(alphabet ? std::move(alphabet) : std::make_shared<Alphabet>()) {}

void ModuleString::push_back(int symbol, std::span<const double> params) {
    // Offsets are 32-bit to keep strings compact; 4 billion parameters is far beyond any tree.
    if (params_.size() + params.size() > std::numeric_limits<std::uint32_t>::max())
        throw Error::input("module string", "more than 4294967295 parameters; lower the derivation length");
    symbols_.push_back(symbol);
    params_.insert(params_.end(), params.begin(), params.end());
    offsets_.push_back(static_cast<std::uint32_t>(params_.size()));
}

void ModuleString::push_back(std::string_view name, std::initializer_list<double> params) { push_back(alphabet_->intern(name), params); }

void ModuleString::append(const ModuleString& other, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) push_back(other.symbol(i), other.params(i));
}

void ModuleString::clear() {
    symbols_.clear();
    params_.clear();
    offsets_.assign(1, 0);
}

void ModuleString::reserve(std::size_t modules, std::size_t params) {
    symbols_.reserve(modules);
    offsets_.reserve(modules + 1);
    params_.reserve(params);
}

std::string format_number(double value) {
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    return std::string(buffer, result.ptr);
}

std::string ModuleString::to_string(std::size_t begin, std::size_t end) const {
    std::string text;
    for (std::size_t i = begin; i < end && i < size(); ++i) {
        text += name(i);
        const auto p = params(i);
        if (p.empty()) continue;
        text += '(';
        for (std::size_t k = 0; k < p.size(); ++k) {
            if (k) text += ',';
            text += format_number(p[k]);
        }
        text += ')';
    }
    return text;
}

std::size_t ModuleString::count(std::string_view name) const {
    const int id = alphabet_->find(name);
    return id < 0 ? 0 : static_cast<std::size_t>(std::count(symbols_.begin(), symbols_.end(), id));
}

bool ModuleString::operator==(const ModuleString& other) const {
    if (size() != other.size()) return false;
    for (std::size_t i = 0; i < size(); ++i) {
        if (name(i) != other.name(i)) return false;
        const auto a = params(i), b = other.params(i);
        if (!std::equal(a.begin(), a.end(), b.begin(), b.end())) return false;
    }
    return true;
}

namespace detail {

bool is_symbol_char(char c) { return c != '\0' && std::strchr("+-&^\\/|[]!$%~'{}.@", c) != nullptr; }

bool at_module_name(Cursor& cursor) {
    cursor.skip_space();
    const char c = cursor.peek();
    return std::isalpha(static_cast<unsigned char>(c)) || is_symbol_char(c);
}

std::string read_module_name(Cursor& cursor, const Alphabet& alphabet) {
    cursor.skip_space();
    const std::string_view rest = cursor.rest();
    for (const std::string& name : alphabet.long_names())
        if (rest.substr(0, name.size()) == name) {
            cursor.set_pos(cursor.pos() + name.size());
            return name;
        }
    const char c = cursor.peek();
    if (std::isalpha(static_cast<unsigned char>(c))) {
        std::size_t n = 1;
        while (n < rest.size() && std::isdigit(static_cast<unsigned char>(rest[n]))) ++n;
        cursor.set_pos(cursor.pos() + n);
        return std::string(rest.substr(0, n));
    }
    if (is_symbol_char(c)) {
        cursor.get();
        return std::string(1, c);
    }
    cursor.fail("expected a module name but found " + cursor.describe_next());
}

}  // namespace detail

ModuleString parse_module_string(std::string_view text, const std::string& source, std::shared_ptr<Alphabet> alphabet) {
    ModuleString result(alphabet ? std::move(alphabet) : std::make_shared<Alphabet>());
    const std::unordered_map<std::string, double> no_constants;
    std::vector<double> params;
    int line = 1;
    std::size_t line_start = 0;
    // Line by line so that errors in multi-line strings (files) report the right line.
    while (line_start <= text.size()) {
        std::size_t line_end = text.find('\n', line_start);
        if (line_end == std::string_view::npos) line_end = text.size();
        detail::Cursor cursor(text.substr(line_start, line_end - line_start), source, line);
        for (;;) {
            cursor.skip_space();
            if (cursor.at_end()) break;
            const std::string name = detail::read_module_name(cursor, result.alphabet());
            params.clear();
            cursor.skip_space();
            if (cursor.consume('(')) {
                for (;;) {
                    params.push_back(detail::parse_constant_expression(cursor, no_constants));
                    cursor.skip_space();
                    if (cursor.consume(')')) break;
                    if (!cursor.consume(',')) cursor.fail("expected ',' or ')' after a parameter of '" + name + "'");
                }
            }
            result.push_back(result.alphabet().intern(name), params);
        }
        line_start = line_end + 1;
        ++line;
    }
    return result;
}

}  // namespace treelobes::lsystem
