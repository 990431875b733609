#include "encode/chain_code.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <sstream>
#include <charconv>
#include <cstdint>
#include <cstdlib>

namespace treelobes::encode {

namespace {

bool is_move(char symbol) { return symbol >= '0' && symbol <= '5'; }

std::string at_character(std::size_t index) { return "at character " + std::to_string(index + 1); }

// Adds the unit move of a symbol 0..5 to `delta`.
void add_move(char symbol, Voxel& delta) {
    const int axis = (symbol - '0') % 3;
    delta[axis] += symbol < '3' ? 1 : -1;
}

bool within_range(const Voxel& v) { return v.cwiseAbs().maxCoeff() <= kMaxVoxelCoordinate; }

}  // namespace

const char* code_kind_name(CodeKind kind) { return kind == CodeKind::F6 ? "F6" : "DBF6"; }

void append_moves(const Voxel& delta, std::string& out) {
    // Ascending symbol order: positive moves (0, 1, 2) before negative ones (3, 4, 5).
    for (int axis = 0; axis < 3; ++axis)
        if (delta[axis] > 0) out.append(static_cast<std::size_t>(delta[axis]), static_cast<char>('0' + axis));
    for (int axis = 0; axis < 3; ++axis)
        if (delta[axis] < 0) out.append(static_cast<std::size_t>(-delta[axis]), static_cast<char>('3' + axis));
}

std::string write_symbols(const std::vector<Internode>& internodes, CodeKind kind) {
    std::string out;
    Voxel previous = Voxel::Zero();
    bool branch_start = true;  // the tree's first internode and the one after each 7 are coded fully
    for (const Internode& internode : internodes) {
        const bool differential = kind == CodeKind::DBF6 && !branch_start;
        append_moves(differential ? Voxel(internode.move - previous) : internode.move, out);
        out += internode.terminator;
        previous = internode.move;
        branch_start = internode.terminator == kTip;
    }
    return out;
}

namespace {

// check_symbols's verdict without branches on the symbols: moves and terminators alternate
// unpredictably, and the mispredicted branches made the check cost as much as decoding the
// skeleton. Returns false on any defect, which the detailed pass then locates and reports.
bool valid_symbols(const std::string& symbols, std::size_t& internodes) {
    if (symbols.empty() || symbols.back() != kTip) return false;
    std::size_t terminators = 0;
    std::int64_t queued_forks = 0, fewest_queued = 0;
    bool unknown = false;
    for (std::size_t i = 0; i + 1 < symbols.size(); ++i) {
        const unsigned digit = static_cast<unsigned>(static_cast<unsigned char>(symbols[i])) - unsigned{'0'};
        unknown |= digit > 8;
        terminators += digit >= 6;
        // A 7 inside the code takes a queued lateral; the count may never go below zero.
        queued_forks += std::int64_t{digit == 6} - std::int64_t{digit == 7};
        fewest_queued = std::min(fewest_queued, queued_forks);
    }
    internodes = terminators + 1;
    return !unknown && fewest_queued >= 0 && queued_forks == 0;
}

}  // namespace

// "10,9,5" -> {10, 9, 5}; blanks around values are allowed, an empty text is an empty list.
std::vector<int> parse_radius_list(const std::string& text, const std::string& context) {
    std::vector<int> radii;
    std::stringstream stream(text);
    std::string item;
    while (std::getline(stream, item, ',')) {
        const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
        const std::string value = first == std::string::npos ? "" : item.substr(first, last - first + 1);
        int radius = 0;
        const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), radius);
        if (value.empty() || error != std::errc() || end != value.data() + value.size() || radius < 0)
            throw Error::input(context, "value " + std::to_string(radii.size() + 1) + " ('" + value + "') is not a non-negative integer");
        radii.push_back(radius);
    }
    if (!text.empty() && text.back() == ',') throw Error::input(context, "trailing comma after the last radius");
    return radii;
}

std::size_t check_symbols(const std::string& symbols, const std::string& context) {
    if (std::size_t internodes = 0; valid_symbols(symbols, internodes)) return internodes;
    if (symbols.empty()) throw Error::input(context, "empty chain code (a tree needs at least one internode ending in 7)");
    std::size_t internodes = 0;
    std::size_t queued_forks = 0;  // laterals announced by a 6 and not yet started
    for (std::size_t i = 0; i < symbols.size(); ++i) {
        const char symbol = symbols[i];
        if (is_move(symbol)) continue;
        if (!is_terminator(symbol))
            throw Error::input(context, std::string("unknown chain code symbol '") + symbol + "' " + at_character(i) +
                                                " (expected 0-5 for moves, 6 fork, 7 tip, 8 end of internode)");
        ++internodes;
        if (symbol == kFork) ++queued_forks;
        if (symbol != kTip || i + 1 == symbols.size()) continue;
        // A 7 inside the code returns to the next queued lateral; there has to be one.
        if (queued_forks == 0)
            throw Error::input(context,
                               "tip symbol 7 " + at_character(i) + " ends the last open branch but the code goes on (a fork 6 is missing)");
        --queued_forks;
    }
    const std::size_t last = symbols.size() - 1;
    if (symbols[last] != kTip) throw Error::input(context, "chain code ends " + at_character(last) + " without the final branch tip 7");
    if (queued_forks > 0)
        throw Error::input(context, std::to_string(queued_forks) +
                                            " fork(s) 6 without a lateral branch: the code ends before every queued lateral was coded");
    return internodes;
}

std::vector<Internode> read_internodes(const ChainCode& code, const std::string& context) {
    const std::size_t count = check_symbols(code.symbols, context);
    if (code.radii.size() != count)
        throw Error::input(context, "radius list has " + std::to_string(code.radii.size()) + " values but the " +
                                            code_kind_name(code.kind) + " code has " + std::to_string(count) +
                                            " internodes (one radius per 6, 7 or 8)");
    std::vector<Internode> internodes;
    internodes.reserve(count);
    Voxel delta = Voxel::Zero();
    Voxel previous = Voxel::Zero();
    bool branch_start = true;
    for (std::size_t i = 0; i < code.symbols.size(); ++i) {
        const char symbol = code.symbols[i];
        if (is_move(symbol)) {
            add_move(symbol, delta);
            continue;
        }
        Internode internode;
        const bool differential = code.kind == CodeKind::DBF6 && !branch_start;
        internode.move = differential ? Voxel(previous + delta) : delta;
        internode.terminator = symbol;
        internode.radius = code.radii[internodes.size()];
        if (internode.radius < 0)
            throw Error::input(
                    context, "radius " + std::to_string(internodes.size() + 1) + " is negative (" + std::to_string(internode.radius) + ")");
        if (!within_range(internode.move))
            throw Error::input(context, "internode ending " + at_character(i) + " moves more than 2^40 voxels (corrupt code)");
        internodes.push_back(internode);
        previous = internode.move;
        branch_start = symbol == kTip;
        delta.setZero();
    }
    return internodes;
}

InternodeVectors internode_vectors(const ChainCode& code, const std::string& context) {
    const std::size_t count = check_symbols(code.symbols, context);
    InternodeVectors out;
    out.kind = code.kind;
    out.radii = code.radii;
    out.vectors.reserve(count);
    out.terminators.reserve(count);
    Voxel delta = Voxel::Zero();
    for (const char symbol : code.symbols) {
        if (is_move(symbol)) {
            add_move(symbol, delta);
            continue;
        }
        out.vectors.push_back(delta);
        out.terminators.push_back(symbol);
        delta.setZero();
    }
    return out;
}

std::string symbol_text(const InternodeVectors& code) {
    std::string symbols;
    for (std::size_t i = 0; i < code.terminators.size(); ++i) {
        append_moves(code.vectors[i], symbols);
        symbols += code.terminators[i];
    }
    return symbols;
}

std::vector<bool> contracted_internodes(const std::vector<Internode>& internodes) {
    std::vector<bool> contracted(internodes.size(), false);
    bool branch_start = true;
    for (std::size_t i = 0; i < internodes.size(); ++i) {
        const Internode& internode = internodes[i];
        if (branch_start && internode.move.isZero() && internode.terminator != kTip) {
            contracted[i] = true;  // the branch still starts at the same vertex
            continue;
        }
        branch_start = internode.terminator == kTip;
    }
    return contracted;
}

SymbolCounts count_symbols(const std::string& symbols) {
    SymbolCounts counts;
    for (char symbol : symbols) {
        if (is_move(symbol)) ++counts.moves;
        if (is_terminator(symbol)) ++counts.internodes;
        if (symbol == kFork) ++counts.forks;
        if (symbol == kTip) ++counts.tips;
    }
    return counts;
}

}  // namespace treelobes::encode
