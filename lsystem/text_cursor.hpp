// Internal to lsystem/: a cursor over one line of L-system text that knows its line and column,
// so every parse error can say "line L, column C: ...". Not part of the public API.
#pragma once

#include "core/error.hpp"

#include <cctype>
#include <string>
#include <string_view>

namespace treelobes::lsystem::detail {

class Cursor {
public:
    // `text` is one line (or a part of one starting at `first_column`, 1-based).
    Cursor(std::string_view text, const std::string& source, int line, int first_column = 1)
            : text_(text), source_(source), line_(line), first_column_(first_column) {}

    bool at_end() const { return pos_ >= text_.size(); }
    char peek(std::size_t ahead = 0) const { return pos_ + ahead < text_.size() ? text_[pos_ + ahead] : '\0'; }
    char get() { return at_end() ? '\0' : text_[pos_++]; }
    void skip_space() {
        while (!at_end() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    }
    bool consume(char c) {
        if (peek() != c) return false;
        ++pos_;
        return true;
    }
    bool consume(std::string_view s) {
        if (text_.substr(pos_, s.size()) != s) return false;
        pos_ += s.size();
        return true;
    }
    std::size_t pos() const { return pos_; }
    void set_pos(std::size_t pos) { pos_ = pos; }
    std::string_view rest() const { return text_.substr(pos_); }
    std::string_view text() const { return text_; }
    int line() const { return line_; }
    int column(std::size_t pos) const { return first_column_ + static_cast<int>(pos); }
    const std::string& source() const { return source_; }

    [[noreturn]] void fail(const std::string& what) const { fail_at(pos_, what); }
    [[noreturn]] void fail_at(std::size_t pos, const std::string& what) const {
        throw Error::input(source_, "line " + std::to_string(line_) + ", column " + std::to_string(column(pos)) + ": " + what);
    }
    // "'x'" for messages, or "end of line".
    std::string describe_next() const {
        if (at_end()) return "end of line";
        return std::string("'") + text_[pos_] + "'";
    }

private:
    std::string_view text_;
    const std::string& source_;
    int line_;
    int first_column_;
    std::size_t pos_ = 0;
};

inline bool is_identifier_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
inline bool is_identifier_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

}  // namespace treelobes::lsystem::detail
