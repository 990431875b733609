// TreeGraph: a rooted tree skeleton. Node 0 is the root; every other node has a parent.
// Children are ordered with the main child first (the continuation of the branch), the
// order that DBF6 coding, LOD and the multiresolution chain rely on.
#pragma once

#include <Eigen/Core>
#include <boost/container/small_vector.hpp>

#include <algorithm>
#include <initializer_list>

#include <string>
#include <vector>

namespace treelobes {

// A node's children: room for two in the node itself (a branch's next vertex and one lateral:
// nearly every vertex of a skeleton), so building a tree allocates only at multi-way forks; a
// heap-allocated std::vector per node made allocation a third of decoding a skeleton. Converts
// to, compares with and is assignable from std::vector<int>, which the modules pass around.
class ChildList : public boost::container::small_vector<int, 2> {
    using Base = boost::container::small_vector<int, 2>;

public:
    using Base::Base;
    ChildList() = default;
    ChildList(std::initializer_list<int> children) : Base(children) {}
    ChildList(const std::vector<int>& children) : Base(children.begin(), children.end()) {}
    ChildList& operator=(const std::vector<int>& children) {
        assign(children.begin(), children.end());
        return *this;
    }
    ChildList& operator=(std::initializer_list<int> children) {
        assign(children.begin(), children.end());
        return *this;
    }
    operator std::vector<int>() const { return std::vector<int>(begin(), end()); }
    friend bool operator==(const ChildList& a, const ChildList& b) { return std::equal(a.begin(), a.end(), b.begin(), b.end()); }
    friend bool operator==(const ChildList& a, const std::vector<int>& b) { return std::equal(a.begin(), a.end(), b.begin(), b.end()); }
};

struct TreeNode {
    Eigen::Vector3f position{0, 0, 0};  // local coordinates (metres)
    float radius = 0.0f;                // metres
    int parent = -1;                    // -1 for the root only
    ChildList children;                 // main child first
};

class TreeGraph {
public:
    Eigen::Vector3d origin{0, 0, 0};  // add to local positions for original coordinates
    std::vector<TreeNode> nodes;

    std::size_t size() const { return nodes.size(); }
    bool empty() const { return nodes.empty(); }

    // Adds a node; parent -1 only for the first node (the root). Returns its index.
    int add_node(const Eigen::Vector3f& position, float radius, int parent);

    // Depth-first pre-order from the root, main child first (the project's one traversal order).
    std::vector<int> preorder() const;

    // Length of the edge from node to its parent (0 for the root).
    float edge_length(int node) const;
    // Total length of all edges below each node (l(u) of Livny et al. 2011, Eq. 1), indexed by node.
    std::vector<float> subtree_lengths() const;
    // Branch order per node: 0 on the trunk, +1 each time a lateral (non-first) child is taken.
    std::vector<int> branch_orders() const;
    // Sum of all edge lengths.
    float total_length() const;
    // Number of nodes without children.
    std::size_t tip_count() const;

    // Reorders every node's children so that the one with the largest subtree length comes
    // first (ties: smallest direction change, then lowest index).
    void order_children_by_subtree_length();

    // Throws Error(InvalidInput) naming `context` when the parent/children links are not one
    // rooted tree with node 0 as root, or a position/radius is not finite.
    void validate(const std::string& context) const;
};

// Keeps the flagged nodes (keep[0] must be true); new_index[old] is the new index of a kept node
// or of its nearest kept ancestor. New nodes are numbered in the input's pre-order.
TreeGraph keep_nodes(const TreeGraph& tree, const std::vector<bool>& keep, std::vector<int>& new_index);
// Chains between branching points: each starts at the root or a fork, follows single-child
// nodes and ends at a tip or the next fork (both ends included).
std::vector<std::vector<int>> tree_chains(const TreeGraph& tree);

}  // namespace treelobes
