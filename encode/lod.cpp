#include "encode/lod.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <deque>

namespace treelobes::encode {

namespace {

// Queue entry of Pseudocode 2: where a lateral's fork symbol sits in C', or that its parent
// branch was removed.
constexpr std::ptrdiff_t kParentRemoved = -1;

// Copies (keep = true) or skips one branch: the symbols from the current position up to and
// including the branch's 7, with one radius per 6, 7 or 8. Forks inside the branch queue the
// position of their 6 in C' (or kParentRemoved) for the laterals they announce.
void transfer_branch(const ChainCode& in, std::size_t& symbol, std::size_t& radius, bool keep, ChainCode& out,
                     std::deque<std::ptrdiff_t>& queue) {
    for (;;) {
        const char c = in.symbols[symbol++];
        if (keep) out.symbols += c;
        if (c != kFork && c != kTip && c != kEndOfInternode) continue;
        if (keep) out.radii.push_back(in.radii[radius]);
        ++radius;
        if (c == kFork) queue.push_back(keep ? static_cast<std::ptrdiff_t>(out.symbols.size()) - 1 : kParentRemoved);
        if (c == kTip) return;
    }
}

}  // namespace

ChainCode reduce_lod(const ChainCode& code, double threshold, const std::string& context) {
    read_internodes(code, context);  // rejects corrupt codes before the unguarded walk below

    ChainCode out;
    out.kind = code.kind;
    std::deque<std::ptrdiff_t> queue;
    std::size_t symbol = 0, radius = 0;
    transfer_branch(code, symbol, radius, /*keep=*/true, out, queue);  // the trunk is never pruned
    while (symbol < code.symbols.size()) {
        // check_symbols guarantees a queued fork for every branch after the trunk.
        const std::ptrdiff_t fork = queue.front();
        queue.pop_front();
        const bool keep = fork != kParentRemoved && code.radii[radius] >= threshold;
        if (!keep && fork != kParentRemoved) out.symbols[static_cast<std::size_t>(fork)] = kEndOfInternode;
        transfer_branch(code, symbol, radius, keep, out, queue);
    }
    return out;
}

std::vector<int> branch_thicknesses(const ChainCode& code) {
    // Branches follow one another in the code, each ending with its tip: the internode after a
    // tip is the first of the next lateral.
    std::vector<int> thicknesses;
    std::size_t radius = 0;
    bool after_tip = false;
    for (const char c : code.symbols) {
        if (c != kFork && c != kTip && c != kEndOfInternode) continue;
        if (radius >= code.radii.size()) break;
        if (after_tip) thicknesses.push_back(code.radii[radius]);
        after_tip = c == kTip;
        ++radius;
    }
    return thicknesses;
}

std::vector<double> lod_thresholds(const std::vector<int>& thicknesses, int levels) {
    if (levels < 1) throw Error::usage("the number of LODs must be at least 1 (got " + std::to_string(levels) + ")");
    std::vector<int> unique = thicknesses;
    std::sort(unique.begin(), unique.end());
    unique.erase(std::unique(unique.begin(), unique.end()), unique.end());
    std::vector<double> thresholds;
    if (unique.empty()) return std::vector<double>(static_cast<std::size_t>(levels - 1), 0.0);
    const std::size_t n = unique.size();
    for (int i = 1; i < levels; ++i) thresholds.push_back(unique[static_cast<std::size_t>(i) * n / static_cast<std::size_t>(levels)]);
    return thresholds;
}

std::vector<ChainCode> lod_chain(const ChainCode& code, const std::vector<double>& thresholds, const std::string& context) {
    std::vector<ChainCode> levels{code};
    for (double threshold : thresholds) levels.push_back(reduce_lod(levels.back(), threshold, context));
    return levels;
}

}  // namespace treelobes::encode
