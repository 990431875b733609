// Helpers shared by the lsystem tests: example files and exact geometry comparison.
#pragma once

#include "core/tree_graph.hpp"
#include "lsystem/turtle.hpp"
#include "support/test_support.hpp"

#include <algorithm>
#include <array>
#include <string>
#include <vector>

namespace treelobes::lsystem::test_util {

inline std::string example(const std::string& name) { return (treelobes::test::source_dir() / "lsystem" / "examples" / name).string(); }

// Every internode as (parent position, position, radius), sorted: two trees with the same edges
// compare equal whatever their node numbering.
using Edge = std::array<float, 7>;
inline std::vector<Edge> edges(const TreeGraph& tree) {
    std::vector<Edge> out;
    for (std::size_t i = 1; i < tree.nodes.size(); ++i) {
        const auto& n = tree.nodes[i];
        const auto& p = tree.nodes[static_cast<std::size_t>(n.parent)].position;
        out.push_back({p.x(), p.y(), p.z(), n.position.x(), n.position.y(), n.position.z(), n.radius});
    }
    std::sort(out.begin(), out.end());
    return out;
}

inline std::vector<std::array<float, 10>> leaves(const TurtleResult& r) {
    std::vector<std::array<float, 10>> out;
    for (const auto& l : r.leaves)
        out.push_back({l.position.x(), l.position.y(), l.position.z(), l.heading.x(), l.heading.y(), l.heading.z(), l.up.x(), l.up.y(),
                       l.up.z(), l.size});
    std::sort(out.begin(), out.end());
    return out;
}

// Position of the last node of the trunk: from the root, follow main children while they stay at
// bracket depth 0.
inline Eigen::Vector3f trunk_top(const TurtleResult& r) {
    int node = 0;
    while (!r.tree.nodes[static_cast<std::size_t>(node)].children.empty()) {
        const int child = r.tree.nodes[static_cast<std::size_t>(node)].children[0];
        if (r.depth[static_cast<std::size_t>(child)] != 0) break;
        node = child;
    }
    return r.tree.nodes[static_cast<std::size_t>(node)].position;
}

}  // namespace treelobes::lsystem::test_util
