#include "core/crs_units.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>

namespace treelobes {

namespace {

bool is_name_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Does `keyword[` (or `keyword(`) start at `at` as a whole word?
bool keyword_at(std::string_view text, std::size_t at, std::string_view keyword) {
    const std::size_t open = at + keyword.size();
    return text.compare(at, keyword.size(), keyword) == 0 && (at == 0 || !is_name_char(text[at - 1])) && open < text.size() &&
           (text[open] == '[' || text[open] == '(');
}

// Offset of `keyword[` as a whole word at or after `from` in `text`; npos when absent.
std::size_t find_keyword(std::string_view text, std::string_view keyword, std::size_t from = 0) {
    for (std::size_t at = text.find(keyword, from); at != std::string_view::npos; at = text.find(keyword, at + 1))
        if (keyword_at(text, at, keyword)) return at;
    return std::string_view::npos;
}

// The bracket matching the one at `open`; npos when unbalanced.
std::size_t matching_bracket(std::string_view text, std::size_t open) {
    int depth = 0;
    bool quoted = false;
    for (std::size_t i = open; i < text.size(); ++i) {
        const char c = text[i];
        if (c == '"') quoted = !quoted;
        if (quoted) continue;
        if (c == '[' || c == '(') ++depth;
        if ((c == ']' || c == ')') && --depth == 0) return i;
    }
    return std::string_view::npos;
}

// `UNIT["name",factor,...]` (or LENGTHUNIT) whose keyword starts at `at`.
std::optional<CrsUnit> unit_at(std::string_view text, std::size_t at, bool angular) {
    const std::size_t quote = text.find('"', at);
    const std::size_t end_quote = quote == std::string_view::npos ? quote : text.find('"', quote + 1);
    if (end_quote == std::string_view::npos) return std::nullopt;
    const std::size_t comma = text.find(',', end_quote);
    if (comma == std::string_view::npos) return std::nullopt;
    const std::string factor(text.substr(comma + 1, 32));
    char* parsed_end = nullptr;
    const double metres = std::strtod(factor.c_str(), &parsed_end);
    if (parsed_end == factor.c_str() || !(metres > 0.0)) return std::nullopt;
    return CrsUnit{std::string(text.substr(quote + 1, end_quote - quote - 1)), angular ? 0.0 : metres, angular};
}

// The UNIT directly inside the node whose body spans [open, close] (not one of a nested node's).
std::optional<CrsUnit> own_unit(std::string_view text, std::size_t open, std::size_t close, bool angular) {
    int depth = 0;
    bool quoted = false;
    for (std::size_t i = open; i < close; ++i) {
        const char c = text[i];
        if (c == '"') quoted = !quoted;
        if (quoted) continue;
        if (c == '[' || c == '(') ++depth;
        if (c == ']' || c == ')') --depth;
        if (depth == 1 && keyword_at(text, i, "UNIT")) return unit_at(text, i, angular);
    }
    return std::nullopt;
}

// The first UNIT or LENGTHUNIT at or after `from` and before `end`; npos when none.
std::size_t first_unit(std::string_view text, std::size_t from, std::size_t end) {
    const std::size_t unit = std::min(find_keyword(text, "LENGTHUNIT", from), find_keyword(text, "UNIT", from));
    return unit < end ? unit : std::string_view::npos;
}

}  // namespace

std::optional<CrsUnit> crs_horizontal_unit(std::string_view wkt) {
    if (const std::size_t at = find_keyword(wkt, "PROJCRS"); at != std::string_view::npos) {
        // The coordinate system's axes carry the unit; the conversion's parameters before them
        // carry their own (a false easting in metres for a CRS in feet).
        const std::size_t cs = find_keyword(wkt, "CS", at);
        if (cs == std::string_view::npos) return std::nullopt;
        const std::size_t unit = first_unit(wkt, cs, wkt.size());
        return unit == std::string_view::npos ? std::nullopt : unit_at(wkt, unit, false);
    }
    if (const std::size_t at = find_keyword(wkt, "PROJCS"); at != std::string_view::npos) {
        const std::size_t open = wkt.find_first_of("[(", at), close = matching_bracket(wkt, open);
        return close == std::string_view::npos ? std::nullopt : own_unit(wkt, open, close, false);
    }
    for (const std::string_view geographic : {"GEOGCRS", "GEOGCS", "GEODCRS"})
        if (find_keyword(wkt, geographic) != std::string_view::npos) return CrsUnit{"degree", 0.0, true};
    return std::nullopt;
}

std::optional<CrsUnit> crs_vertical_unit(std::string_view wkt) {
    for (const std::string_view vertical : {"VERTCRS", "VERTICALCRS"})
        if (const std::size_t at = find_keyword(wkt, vertical); at != std::string_view::npos) {
            const std::size_t open = wkt.find_first_of("[(", at), close = matching_bracket(wkt, open);
            const std::size_t cs = close == std::string_view::npos ? close : find_keyword(wkt, "CS", open);
            if (cs == std::string_view::npos || cs > close) return std::nullopt;
            const std::size_t unit = first_unit(wkt, cs, close);
            return unit == std::string_view::npos ? std::nullopt : unit_at(wkt, unit, false);
        }
    if (const std::size_t at = find_keyword(wkt, "VERT_CS"); at != std::string_view::npos) {
        const std::size_t open = wkt.find_first_of("[(", at), close = matching_bracket(wkt, open);
        return close == std::string_view::npos ? std::nullopt : own_unit(wkt, open, close, false);
    }
    return std::nullopt;
}

std::optional<CrsUnit> epsg_linear_unit(int code) {
    switch (code) {
        case 9001:
            return CrsUnit{"metre", 1.0, false};
        case 9002:
            return CrsUnit{"foot", 0.3048, false};
        case 9003:
            return CrsUnit{"US survey foot", 1200.0 / 3937.0, false};
        case 9005:
            return CrsUnit{"Clarke's foot", 0.3047972654, false};
        case 9036:
            return CrsUnit{"kilometre", 1000.0, false};
        case 9041:
            return CrsUnit{"British foot (Sears 1922)", 0.304799471538676, false};
        case 9070:
            return CrsUnit{"British foot (1936)", 0.3048007491, false};
        case 9096:
            return CrsUnit{"yard", 0.9144, false};
        default:
            return std::nullopt;
    }
}

}  // namespace treelobes
