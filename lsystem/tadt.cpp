#include "lsystem/tadt.hpp"

#include "core/error.hpp"

#include <algorithm>

namespace treelobes::lsystem {

namespace {

// Length of each symbol of the alphabet: -1 = not a length module.
std::vector<char> length_symbols(const Alphabet& alphabet, const TadtOptions& options) {
    std::vector<char> is_length(alphabet.size(), 0);
    for (const auto& name : options.length_modules) {
        const int id = alphabet.find(name);
        if (id >= 0) is_length[static_cast<std::size_t>(id)] = 1;
    }
    return is_length;
}

int add_child(Tadt& tadt, int parent, bool lateral, std::size_t begin) {
    TadtNode node;
    node.parent = parent;
    node.lateral = lateral;
    node.begin = node.end = begin;
    tadt.nodes.push_back(node);
    const int id = static_cast<int>(tadt.nodes.size() - 1);
    tadt.nodes[static_cast<std::size_t>(parent)].children.push_back(id);
    return id;
}

}  // namespace

Tadt build_tadt(const ModuleString& string, const TadtOptions& options, const std::string& source) {
    Tadt tadt{string, {}};
    tadt.nodes.emplace_back();
    const std::vector<char> is_length = length_symbols(string.alphabet(), options);
    std::vector<int> stack;
    int current = 0;
    bool open = true;  // may the current node still take modules? (not after one of its ']')
    for (std::size_t i = 0; i < string.size(); ++i) {
        const int symbol = string.symbol(i);
        if (symbol == Alphabet::kPush) {
            stack.push_back(current);
            current = add_child(tadt, current, true, i + 1);
            open = true;
        } else if (symbol == Alphabet::kPop) {
            if (stack.empty()) throw Error::input(source, "']' at module " + std::to_string(i) + " has no matching '['");
            current = stack.back();
            stack.pop_back();
            open = false;
        } else {
            if (!open) {
                current = add_child(tadt, current, false, i);
                open = true;
            }
            TadtNode& node = tadt.nodes[static_cast<std::size_t>(current)];
            if (node.end == node.begin) node.begin = i;  // first module of the run
            node.end = i + 1;
            if (static_cast<std::size_t>(symbol) < is_length.size() && is_length[static_cast<std::size_t>(symbol)])
                node.length += string.param_or(i, options.default_length);
        }
    }
    if (!stack.empty()) throw Error::input(source, "a '[' is never closed (" + std::to_string(stack.size()) + " open)");
    // Children always have larger indices than their parent: one backward pass accumulates.
    for (std::size_t n = tadt.nodes.size(); n-- > 0;) {
        TadtNode& node = tadt.nodes[n];
        node.subtree_length += node.length;
        if (node.parent >= 0) tadt.nodes[static_cast<std::size_t>(node.parent)].subtree_length += node.subtree_length;
    }
    return tadt;
}

}  // namespace treelobes::lsystem
