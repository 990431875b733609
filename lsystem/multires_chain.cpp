#include "lsystem/multires_chain.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace treelobes::lsystem {

namespace {

// a beats b only by more than a relative 1e-9: sums of the same lengths in another order are ties.
bool greater_than(double a, double b) { return a > b + 1e-9 * std::max({1.0, std::fabs(a), std::fabs(b)}); }

// Remaining metric values over the unvisited part of each subtree, kept up to date as paths are
// visited. Node indices grow from parent to child (build_tadt), so index order is a topological order.
class Metrics {
public:
    Metrics(const Tadt& tadt, ChainMetric metric) : tadt_(tadt), metric_(metric) {
        const std::size_t n = tadt.nodes.size();
        visited_.assign(n, 0);
        unvisited_.assign(n, 0);
        value_.assign(n, 0.0);
        for (std::size_t i = n; i-- > 0;) recompute(static_cast<int>(i));
    }

    bool visited(int n) const { return visited_[static_cast<std::size_t>(n)]; }
    bool exhausted(int n) const { return unvisited_[static_cast<std::size_t>(n)] == 0; }
    double value(int n) const { return value_[static_cast<std::size_t>(n)]; }
    void visit(int n) { visited_[static_cast<std::size_t>(n)] = 1; }

    // Child with the highest value among those with unvisited nodes; ties to the first. -1 if none.
    int best_child(int n) const {
        int best = -1;
        for (int c : tadt_.nodes[static_cast<std::size_t>(n)].children) {
            if (exhausted(c)) continue;
            if (best < 0 || greater_than(value(c), value(best))) best = c;
        }
        return best;
    }

    // Updates a node from its children (call bottom-up along a visited path).
    void recompute(int n) {
        const TadtNode& node = tadt_.nodes[static_cast<std::size_t>(n)];
        const bool open = !visited(n);
        std::size_t unvisited = open ? 1 : 0;
        double sum = 0.0, longest = 0.0, open_children = 0.0;
        for (int c : node.children) {
            unvisited += unvisited_[static_cast<std::size_t>(c)];
            sum += value(c);
            longest = std::max(longest, value(c));
            if (!visited(c)) open_children += 1.0;
        }
        unvisited_[static_cast<std::size_t>(n)] = unvisited;
        double& v = value_[static_cast<std::size_t>(n)];
        switch (metric_) {
            case ChainMetric::branching_length:
                v = (open ? node.length : 0.0) + sum;
                break;
            case ChainMetric::descendants:
                v = static_cast<double>(unvisited);
                break;
            case ChainMetric::longest_path:
                v = (open ? 1.0 : 0.0) + longest;
                break;
            case ChainMetric::children:
                v = open_children;
                break;
        }
    }

private:
    const Tadt& tadt_;
    ChainMetric metric_;
    std::vector<char> visited_;
    std::vector<std::size_t> unvisited_;
    std::vector<double> value_;
};

class ChainBuilder {
public:
    ChainBuilder(MultiresChain& chain) : chain_(chain), tadt_(chain.tadt) { chain_.save_slot.assign(tadt_.nodes.size(), -1); }

    void emit_node(int n) {
        chain_.entries.push_back({ChainEntry::Kind::node, n});
        if (tadt_.nodes[static_cast<std::size_t>(n)].children.size() > 1) {
            chain_.save_slot[static_cast<std::size_t>(n)] = chain_.save_count++;
            chain_.entries.push_back({ChainEntry::Kind::save, n});
        }
    }
    void emit_restore(int n) {
        chain_.restores.push_back(chain_.entries.size());
        chain_.entries.push_back({ChainEntry::Kind::restore, n});
    }

    void greedy(ChainMetric metric) {
        Metrics metrics(tadt_, metric);
        std::vector<int> path;
        metrics.visit(0);
        emit_node(0);
        bool first = true;
        while (!metrics.exhausted(0)) {
            path.assign(1, 0);
            // Down through visited nodes to the branch point, then on through unvisited ones to a
            // leaf; the branch point is announced by RESTORE (except on the very first path).
            bool fresh = false;
            for (int node = 0, child; (child = metrics.best_child(node)) >= 0; node = child) {
                if (!metrics.visited(child)) {
                    if (!fresh && !first) emit_restore(node);
                    fresh = true;
                    metrics.visit(child);
                    emit_node(child);
                }
                path.push_back(child);
            }
            first = false;
            for (auto it = path.rbegin(); it != path.rend(); ++it) metrics.recompute(*it);
        }
    }

    void depth_first(ChainMetric metric) {
        const Metrics metrics(tadt_, metric);  // static values: nothing is visited yet
        // Children of every node by decreasing metric; stable, so ties keep string order.
        auto ordered = [&](int n) {
            std::vector<int> children = tadt_.nodes[static_cast<std::size_t>(n)].children;
            std::stable_sort(children.begin(), children.end(),
                             [&](int a, int b) { return greater_than(metrics.value(a), metrics.value(b)); });
            return children;
        };
        struct Frame {
            int node;
            std::vector<int> children;
            std::size_t next = 0;
        };
        std::vector<Frame> stack;
        emit_node(0);
        stack.push_back({0, ordered(0)});
        while (!stack.empty()) {
            Frame& top = stack.back();
            if (top.next == top.children.size()) {
                stack.pop_back();
                continue;
            }
            const int child = top.children[top.next];
            if (top.next++ > 0) emit_restore(top.node);
            emit_node(child);
            stack.push_back({child, ordered(child)});
        }
    }

private:
    MultiresChain& chain_;
    const Tadt& tadt_;
};

// Sum over leaves of their depth: the number of steps of the greedy descents.
std::size_t greedy_work(const Tadt& tadt) {
    std::vector<std::size_t> depth(tadt.nodes.size(), 0);
    std::size_t work = 0;
    for (std::size_t n = 1; n < tadt.nodes.size(); ++n) {
        const TadtNode& node = tadt.nodes[n];
        depth[n] = depth[static_cast<std::size_t>(node.parent)] + 1;
    }
    for (std::size_t n = 0; n < tadt.nodes.size(); ++n)
        if (tadt.nodes[n].children.empty()) work += depth[n] + 1;
    return work;
}

void accumulate_lod_lengths(MultiresChain& chain) {
    chain.lod_length.assign(chain.lod_count(), 0.0);
    double length = 0.0;
    std::size_t lod = 0;
    for (std::size_t e = 0; e < chain.entries.size(); ++e) {
        while (lod < chain.restores.size() && chain.restores[lod] == e) chain.lod_length[lod++] = length;
        if (chain.entries[e].kind == ChainEntry::Kind::node)
            length += chain.tadt.nodes[static_cast<std::size_t>(chain.entries[e].node)].length;
    }
    chain.lod_length.back() = length;
}

std::string node_content(const Tadt& tadt, int n) {
    const TadtNode& node = tadt.nodes[static_cast<std::size_t>(n)];
    return node.begin == node.end ? "<empty>" : tadt.string.to_string(node.begin, node.end);
}

}  // namespace

std::string_view to_string(ChainMetric metric) {
    switch (metric) {
        case ChainMetric::branching_length:
            return "branching-length";
        case ChainMetric::children:
            return "children";
        case ChainMetric::descendants:
            return "descendants";
        case ChainMetric::longest_path:
            return "longest-path";
    }
    return "branching-length";
}

std::optional<ChainMetric> parse_chain_metric(std::string_view name) {
    std::string n(name);
    std::replace(n.begin(), n.end(), '_', '-');
    for (ChainMetric m : {ChainMetric::branching_length, ChainMetric::children, ChainMetric::descendants, ChainMetric::longest_path})
        if (to_string(m) == n) return m;
    return std::nullopt;
}

std::string_view to_string(ChainOrder order) { return order == ChainOrder::greedy ? "greedy" : "depth-first"; }

std::optional<ChainOrder> parse_chain_order(std::string_view name) {
    std::string n(name);
    std::replace(n.begin(), n.end(), '_', '-');
    if (n == "greedy") return ChainOrder::greedy;
    if (n == "depth-first") return ChainOrder::depth_first;
    return std::nullopt;
}

MultiresChain build_multires_chain(Tadt tadt, const MultiresOptions& options) {
    MultiresChain chain;
    chain.tadt = std::move(tadt);
    chain.metric = options.metric;
    chain.order = options.order;
    if (chain.tadt.nodes.empty()) chain.tadt.nodes.emplace_back();
    chain.entries.reserve(chain.tadt.nodes.size() * 2);
    ChainBuilder builder(chain);
    if (options.order == ChainOrder::greedy) {
        const std::size_t work = greedy_work(chain.tadt);
        if (work > options.max_greedy_work)
            throw Error::input("multiresolution chain", "the greedy order would take about " + std::to_string(work) +
                                                                " steps on this tADT (" + std::to_string(chain.tadt.nodes.size()) +
                                                                " nodes, deep nesting); use the depth-first order");
        builder.greedy(options.metric);
    } else {
        builder.depth_first(options.metric);
    }
    accumulate_lod_lengths(chain);
    return chain;
}

MultiresChain build_multires_chain(const ModuleString& string, const MultiresOptions& options, const std::string& source) {
    return build_multires_chain(build_tadt(string, options.tadt, source), options);
}

std::string format_chain(const MultiresChain& chain, ChainLabels labels, std::size_t end) {
    std::string text;
    end = std::min(end, chain.entries.size());
    auto label = [&](int n) {
        if (labels == ChainLabels::content) return node_content(chain.tadt, n);
        std::string id = "n";  // (not "n" + to_string: GCC 12 warns falsely, -Wrestrict)
        id += std::to_string(n);
        return id;
    };
    for (std::size_t e = 0; e < end; ++e) {
        const ChainEntry& entry = chain.entries[e];
        if (e) text += ' ';
        switch (entry.kind) {
            case ChainEntry::Kind::node:
                text += node_content(chain.tadt, entry.node);
                break;
            case ChainEntry::Kind::save:
                text += "SAVE(" + label(entry.node) + ")";
                break;
            case ChainEntry::Kind::restore:
                text += "RESTORE(" + label(entry.node) + ")";
                break;
        }
    }
    return text;
}

std::string chain_file_text(const MultiresChain& chain) {
    std::string text = "# treelobes multiresolution chain (Lluch et al. 2010): metric " + std::string(to_string(chain.metric)) +
                       ", order " + std::string(to_string(chain.order)) + "\n# tadt_nodes " + std::to_string(chain.tadt.nodes.size()) +
                       ", entries " + std::to_string(chain.entries.size()) + ", lods " + std::to_string(chain.lod_count()) +
                       "\n# LOD k = the entries before the (k+1)-th RESTORE\n";
    for (const ChainEntry& entry : chain.entries) {
        const std::string id = std::to_string(entry.node);
        switch (entry.kind) {
            case ChainEntry::Kind::node: {
                const TadtNode& node = chain.tadt.nodes[static_cast<std::size_t>(entry.node)];
                const char* kind = node.parent < 0 ? "root" : node.lateral ? "lateral" : "continuation";
                text += "node " + id + " " + kind + " " + chain.tadt.string.to_string(node.begin, node.end) + "\n";
                break;
            }
            case ChainEntry::Kind::save:
                text += "SAVE " + id + "\n";
                break;
            case ChainEntry::Kind::restore:
                text += "RESTORE " + id + "\n";
                break;
        }
    }
    return text;
}

TurtleResult interpret_chain(const MultiresChain& chain, std::size_t end, const TurtleOptions& options) {
    const ModuleString& string = chain.tadt.string;
    Turtle turtle(string.alphabet(), options);
    std::vector<Turtle::State> saved(static_cast<std::size_t>(chain.save_count));
    end = std::min(end, chain.entries.size());
    for (std::size_t e = 0; e < end; ++e) {
        const ChainEntry& entry = chain.entries[e];
        const TadtNode& node = chain.tadt.nodes[static_cast<std::size_t>(entry.node)];
        const auto slot = static_cast<std::size_t>(chain.save_slot[static_cast<std::size_t>(entry.node)]);
        switch (entry.kind) {
            case ChainEntry::Kind::node:
                if (node.lateral) turtle.enter_lateral();
                turtle.apply(string, node.begin, node.end);
                break;
            case ChainEntry::Kind::save:
                saved[slot] = turtle.state();
                break;
            case ChainEntry::Kind::restore:
                turtle.set_state(saved[slot]);
                break;
        }
    }
    return turtle.take_result();
}

}  // namespace treelobes::lsystem
