#include "core/tree_graph.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace treelobes {

int TreeGraph::add_node(const Eigen::Vector3f& position, float radius, int parent) {
    const int index = static_cast<int>(nodes.size());
    if (parent < -1 || parent >= index || (parent == -1) != (index == 0))
        throw Error(ExitCode::Internal,
                    "TreeGraph::add_node: node " + std::to_string(index) + " given invalid parent " + std::to_string(parent));
    TreeNode node;
    node.position = position;
    node.radius = radius;
    node.parent = parent;
    nodes.push_back(node);
    if (parent >= 0) nodes[parent].children.push_back(index);
    return index;
}

std::vector<int> TreeGraph::preorder() const {
    std::vector<int> order;
    if (nodes.empty()) return order;
    order.reserve(nodes.size());
    std::vector<int> stack{0};
    while (!stack.empty()) {
        const int node = stack.back();
        stack.pop_back();
        order.push_back(node);
        const auto& children = nodes[node].children;
        // Push in reverse so that the main child (first) is visited first.
        for (auto it = children.rbegin(); it != children.rend(); ++it) stack.push_back(*it);
    }
    return order;
}

float TreeGraph::edge_length(int node) const {
    const int parent = nodes[node].parent;
    return parent < 0 ? 0.0f : (nodes[node].position - nodes[parent].position).norm();
}

std::vector<float> TreeGraph::subtree_lengths() const {
    std::vector<float> length(nodes.size(), 0.0f);
    const std::vector<int> order = preorder();
    // Reverse pre-order visits every child before its parent.
    for (auto it = order.rbegin(); it != order.rend(); ++it) {
        const int node = *it;
        const int parent = nodes[node].parent;
        if (parent >= 0) length[parent] += length[node] + edge_length(node);
    }
    return length;
}

std::vector<int> TreeGraph::branch_orders() const {
    std::vector<int> order(nodes.size(), 0);
    for (int node : preorder()) {
        const auto& children = nodes[node].children;
        for (std::size_t k = 0; k < children.size(); ++k) order[children[k]] = order[node] + (k == 0 ? 0 : 1);
    }
    return order;
}

float TreeGraph::total_length() const {
    double sum = 0.0;
    for (std::size_t i = 1; i < nodes.size(); ++i) sum += edge_length(static_cast<int>(i));
    return static_cast<float>(sum);
}

std::size_t TreeGraph::tip_count() const {
    return static_cast<std::size_t>(std::count_if(nodes.begin(), nodes.end(), [](const TreeNode& n) { return n.children.empty(); }));
}

void TreeGraph::order_children_by_subtree_length() {
    const std::vector<float> length = subtree_lengths();
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        auto& node = nodes[i];
        if (node.children.size() < 2) continue;
        // Direction of the incoming edge; the root continues straight up.
        Eigen::Vector3f incoming = node.parent >= 0 ? (node.position - nodes[node.parent].position) : Eigen::Vector3f(0, 0, 1);
        if (incoming.norm() > 0) incoming.normalize();
        auto turn = [&](int child) {
            Eigen::Vector3f d = nodes[child].position - node.position;
            const float n = d.norm();
            return n > 0 ? 1.0f - incoming.dot(d / n) : 1.0f;
        };
        auto weight = [&](int child) { return length[child] + edge_length(child); };
        std::stable_sort(node.children.begin(), node.children.end(), [&](int a, int b) {
            if (weight(a) != weight(b)) return weight(a) > weight(b);
            if (turn(a) != turn(b)) return turn(a) < turn(b);
            return a < b;
        });
    }
}

void TreeGraph::validate(const std::string& context) const {
    if (nodes.empty()) throw Error::input(context, "tree has no nodes");
    if (nodes[0].parent != -1) throw Error::input(context, "node 0 (the root) has a parent");
    std::vector<int> seen(nodes.size(), 0);
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const auto& node = nodes[i];
        if (!node.position.allFinite() || !std::isfinite(node.radius))
            throw Error::input(context, "node " + std::to_string(i) + " has a non-finite position or radius");
        if (i > 0 && (node.parent < 0 || node.parent >= static_cast<int>(nodes.size())))
            throw Error::input(context, "node " + std::to_string(i) + " has no valid parent");
        for (int child : node.children) {
            if (child <= 0 || child >= static_cast<int>(nodes.size()) || nodes[child].parent != static_cast<int>(i))
                throw Error::input(context, "node " + std::to_string(i) + " lists child " + std::to_string(child) +
                                                    " whose parent is not " + std::to_string(i));
            ++seen[child];
        }
    }
    for (std::size_t i = 1; i < nodes.size(); ++i)
        if (seen[i] != 1) throw Error::input(context, "node " + std::to_string(i) + " is not listed exactly once as a child");
    if (preorder().size() != nodes.size()) throw Error::input(context, "the tree contains a cycle or nodes unreachable from the root");
}

TreeGraph keep_nodes(const TreeGraph& tree, const std::vector<bool>& keep, std::vector<int>& new_index) {
    if (tree.empty() || !keep[0]) throw Error(ExitCode::Internal, "keep_nodes: the root must be kept");
    TreeGraph out;
    out.origin = tree.origin;
    new_index.assign(tree.size(), -1);
    for (int u : tree.preorder()) {
        const int parent = tree.nodes[u].parent;
        if (keep[u])
            new_index[u] = out.add_node(tree.nodes[u].position, tree.nodes[u].radius, parent < 0 ? -1 : new_index[parent]);
        else
            new_index[u] = new_index[parent];
    }
    return out;
}

std::vector<std::vector<int>> tree_chains(const TreeGraph& tree) {
    std::vector<std::vector<int>> chains;
    for (int start : tree.preorder()) {
        const auto& kids = tree.nodes[start].children;
        if (start != 0 && kids.size() < 2) continue;
        for (int child : kids) {
            std::vector<int> chain{start, child};
            while (tree.nodes[chain.back()].children.size() == 1) chain.push_back(tree.nodes[chain.back()].children.front());
            chains.push_back(std::move(chain));
        }
    }
    return chains;
}

}  // namespace treelobes
