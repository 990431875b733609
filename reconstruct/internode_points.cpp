#include "reconstruct/internode_points.hpp"

namespace treelobes {

InternodePoints group_by_internode(std::span<const int> point_internode, std::size_t nodes) {
    auto valid = [nodes](int u) { return u > 0 && static_cast<std::size_t>(u) < nodes; };
    InternodePoints g;
    g.start.assign(nodes + 1, 0);
    for (int u : point_internode)
        if (valid(u)) ++g.start[static_cast<std::size_t>(u) + 1];
    for (std::size_t u = 0; u < nodes; ++u) g.start[u + 1] += g.start[u];
    g.index.resize(g.start[nodes]);
    std::vector<std::size_t> fill(g.start.begin(), g.start.end() - 1);
    for (std::size_t i = 0; i < point_internode.size(); ++i)
        if (valid(point_internode[i])) g.index[fill[static_cast<std::size_t>(point_internode[i])]++] = static_cast<int>(i);
    return g;
}

}  // namespace treelobes
