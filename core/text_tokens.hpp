// Blank-separated tokens of one line of a text format (OBJ, OFF), as views into the line.
#pragma once

#include <string_view>

namespace treelobes {

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

inline std::string_view trimmed(std::string_view s) {
    while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
    while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
    return s;
}

// Splits off the next blank-separated token of `line` (empty at the end).
inline std::string_view next_token(std::string_view& line) {
    std::size_t i = 0;
    while (i < line.size() && is_blank(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !is_blank(line[j])) ++j;
    const std::string_view token = line.substr(i, j - i);
    line.remove_prefix(j);
    return token;
}

}  // namespace treelobes
