// Multiresolution chain of Lluch et al. 2010 (via Ong's seminar report, §3.1 and §3.3): the tADT linearised so
// that every prefix is a coarser tree, with SAVE(n) / RESTORE(n) entries instead of brackets.
//
// Traversal: from the root, always continue into the child with the highest metric (ties, within
// a relative 1e-9, go to the first child in string order). A node with more than one child emits
// SAVE(n) after its own entry. After reaching a leaf, the metric values along the path are
// updated (the visited nodes no longer count), and the traversal resumes at a saved node that
// still has unvisited children, announced by RESTORE(n). Two readings of "resumes":
//   greedy (default): descend again from the root by the *updated* metric; the first visited node
//       whose chosen child is unvisited is restored. The next path is always the one of largest
//       remaining metric, so each RESTORE adds the most important remaining branch (coarse to fine).
//   depth_first: restore the most recently saved node with unvisited children (a stack); the
//       metric then only orders the children of each node.
// Both give the chain of Ong's seminar report on Lluch et al. 2010, §3.1, `C1 SAVE(C1) C2 SAVE(C2) C3 RESTORE(C2) C4 RESTORE(C1) C5`.
//
// Metrics, evaluated on the unvisited part of a node's subtree (the node itself included):
//   branching_length  sum of the tADT lengths (the paper's choice)
//   descendants       number of unvisited nodes
//   longest_path      largest number of unvisited nodes on a downward path
//   children          number of unvisited children
// Before any visit these are the static metrics of the paper (descendants and longest path count
// the node itself, which does not change their order among siblings).
//
// LOD k (k = 0 .. lod_count()-1) is the prefix of entries before the (k+1)-th RESTORE: LOD 0 is the
// first root-to-leaf path, each further level adds one branch, the last level is the whole tree.
#pragma once

#include "lsystem/tadt.hpp"
#include "lsystem/turtle.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace treelobes::lsystem {

enum class ChainMetric { branching_length, children, descendants, longest_path };
enum class ChainOrder { greedy, depth_first };

// "branching-length", "children", "descendants", "longest-path" (underscores accepted too).
std::string_view to_string(ChainMetric metric);
std::optional<ChainMetric> parse_chain_metric(std::string_view name);
std::string_view to_string(ChainOrder order);  // "greedy", "depth-first"
std::optional<ChainOrder> parse_chain_order(std::string_view name);

struct MultiresOptions {
    ChainMetric metric = ChainMetric::branching_length;
    ChainOrder order = ChainOrder::greedy;
    TadtOptions tadt;
    // The greedy order re-descends from the root for every leaf: its cost is about the sum of the
    // leaves' depths. Above this budget build_multires_chain throws instead of running for minutes
    // (combs such as F[F]F[F]... with 10^5 branches); depth_first is linear and has no limit.
    std::size_t max_greedy_work = 200'000'000;
};

struct ChainEntry {
    enum class Kind : unsigned char { node, save, restore };
    Kind kind = Kind::node;
    int node = 0;  // tADT node
};

struct MultiresChain {
    Tadt tadt;
    ChainMetric metric = ChainMetric::branching_length;
    ChainOrder order = ChainOrder::greedy;
    std::vector<ChainEntry> entries;
    std::vector<std::size_t> restores;  // entry index of every RESTORE, in chain order
    std::vector<int> save_slot;         // per tADT node: index of its saved state, -1 if never saved
    int save_count = 0;
    // Per LOD: total tADT length of its nodes. With the greedy branching-length order the levels
    // that add length come first; trailing levels that add none only hold modules without length
    // (apices, leaves), which a renderer may skip.
    std::vector<double> lod_length;

    std::size_t lod_count() const { return restores.size() + 1; }
    // Number of entries in LOD k (clamped to the last level).
    std::size_t lod_end(std::size_t k) const { return k < restores.size() ? restores[k] : entries.size(); }
};

MultiresChain build_multires_chain(Tadt tadt, const MultiresOptions& options = {});
// Builds the tADT first (Error::input naming `source` for unbalanced brackets).
MultiresChain build_multires_chain(const ModuleString& string, const MultiresOptions& options = {},
                                   const std::string& source = "module string");

// The notation of Ong's seminar report on Lluch et al. 2010, §3.1: entries separated by spaces, a node as its modules, SAVE(x)/RESTORE(x)
// labelled by the node's modules (`content`, as in the report) or by `n<id>`. Empty nodes print as
// `<empty>`. Only the first `end` entries (default: all).
enum class ChainLabels { content, node_id };
std::string format_chain(const MultiresChain& chain, ChainLabels labels = ChainLabels::content,
                         std::size_t end = static_cast<std::size_t>(-1));

// The chain file of `treelobes multires`: a commented header, then one entry per line:
// `node <id> root|lateral|continuation <modules>`, `SAVE <id>`, `RESTORE <id>`.
std::string chain_file_text(const MultiresChain& chain);

// Interprets the first `end` entries with the turtle: node entries run their modules (a lateral
// node first enters a branch, like '['), SAVE(n) stores the turtle state, RESTORE(n) reloads it.
// The whole chain gives exactly the geometry of interpreting the original string.
TurtleResult interpret_chain(const MultiresChain& chain, std::size_t end, const TurtleOptions& options = {});
inline TurtleResult extract_lod(const MultiresChain& chain, std::size_t lod, const TurtleOptions& options = {}) {
    return interpret_chain(chain, chain.lod_end(lod), options);
}

}  // namespace treelobes::lsystem
