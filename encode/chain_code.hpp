// The F6 / DBF6 chain code of Strnad et al. 2020, §3.1 as a string of symbols (Table 1):
//   0..5  moves +x +y +z -x -y -z (one voxel each)
//   6     fork: the internode ends at a fork; the main child follows, the first lateral is queued
//   7     branch tip: the internode ends the branch; the next queued lateral follows
//   8     end of internode: the branch continues with one child
// Every 6, 7 or 8 terminates exactly one internode, and the radius list R has one integer per
// internode in the same order. This header converts between the string and a stream of
// internodes with absolute moves; tree_code.hpp maps trees onto such streams.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace treelobes::encode {

enum class CodeKind {
    F6,    // every internode codes its full move Δv
    DBF6,  // differential: only the first internode of each branch is coded fully (§3.1, Fig. 6)
};
const char* code_kind_name(CodeKind kind);

inline constexpr char kFork = '6';
inline constexpr char kTip = '7';
inline constexpr char kEndOfInternode = '8';
inline constexpr bool is_terminator(char symbol) { return symbol == kFork || symbol == kTip || symbol == kEndOfInternode; }

// Voxel coordinates and moves. 64-bit because DBF6 corrections accumulate: a corrupt code of n
// symbols can describe coordinates of order n^3, which must be rejected, not overflow.
using Voxel = Eigen::Matrix<std::int64_t, 3, 1>;

// Decoded coordinates beyond this magnitude are rejected as corrupt (2^40 voxels).
inline constexpr std::int64_t kMaxVoxelCoordinate = std::int64_t{1} << 40;

// One internode of a code stream.
struct Internode {
    Voxel move = Voxel::Zero();  // Δv = v(child) - v(parent), absolute (never the DBF6 correction)
    char terminator = kTip;      // kFork, kTip or kEndOfInternode
    int radius = 0;              // radius of the internode's child vertex, in radius units
};

// A chain code and its radius list (C and R of Pseudocode 1 and 2).
struct ChainCode {
    CodeKind kind = CodeKind::DBF6;
    std::string symbols;
    std::vector<int> radii;  // one per internode, i.e. per 6, 7 or 8 in `symbols`
};

// A chain code as a stream decoder produces it before it would become text: per internode the
// vector its moves add up to (for DBF6 the correction wherever the code has one), its
// terminator and its radius. Decoding a forest builds skeletons from this form directly.
struct InternodeVectors {
    CodeKind kind = CodeKind::DBF6;
    std::vector<Voxel> vectors;
    std::vector<char> terminators;  // kFork, kTip or kEndOfInternode
    std::vector<int> radii;
};

// Appends the moves of `delta` in ascending symbol order, e.g. (2, 1, -3) -> "001555",
// (-1, 2, 0) -> "113" (§3.1: clustering equal moves helps the later compression).
void append_moves(const Voxel& delta, std::string& out);

// The symbol string of an internode stream. DBF6 codes the first internode of the stream and
// every internode after a 7 fully, every other one as the correction Δv - Δv(previous).
std::string write_symbols(const std::vector<Internode>& internodes, CodeKind kind);

// Number of internodes of a code after checking it symbol by symbol: only 0..8, ends with the
// final 7, every 7 but the last one has a queued fork to return to, and no fork is left without
// its lateral. Throws Error(InvalidInput) naming `context` and the 1-based character otherwise.
std::size_t check_symbols(const std::string& symbols, const std::string& context);

// A radius list as text, "10,9,5" -> {10, 9, 5} (blanks around values allowed, empty text: no
// radii). Throws Error(InvalidInput) naming `context` and the value that is not a
// non-negative integer.
std::vector<int> parse_radius_list(const std::string& text, const std::string& context);

// Parses a checked code and its radii back into internodes with absolute moves. Throws
// Error(InvalidInput) for any defect of check_symbols, a radius list whose length differs from
// the internode count, negative radii, or moves beyond kMaxVoxelCoordinate.
std::vector<Internode> read_internodes(const ChainCode& code, const std::string& context);

// A checked code (check_symbols) in internode form, and back.
InternodeVectors internode_vectors(const ChainCode& code, const std::string& context);
std::string symbol_text(const InternodeVectors& code);

// Which internodes the decoder contracts into the vertex their branch starts from: leading
// internodes of a branch (the trunk or a lateral) with a zero move that do not end the branch.
// They are the zero-length internodes that code multi-way forks ("7 6...6", §3.1), the root's
// fork when the root has several children, and such forks turned into 8 by LOD pruning. The
// encoder uses the same rule to know which of its internodes become tree nodes.
std::vector<bool> contracted_internodes(const std::vector<Internode>& internodes);

// Counts of a code: internodes (6, 7 and 8), forks (6) and tips (7).
struct SymbolCounts {
    std::size_t internodes = 0;
    std::size_t forks = 0;
    std::size_t tips = 0;
    std::size_t moves = 0;
};
SymbolCounts count_symbols(const std::string& symbols);

}  // namespace treelobes::encode
