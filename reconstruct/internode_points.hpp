// Input points grouped by the skeleton internode they belong to, for the stages that re-place
// nodes on their own points (recentre, cylinder_axes).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace treelobes {

struct InternodePoints {
    std::vector<std::size_t> start;  // the points of node u's internode are index[start[u] .. start[u + 1])
    std::vector<int> index;          // point indices, in input order within each internode
};

// Counting sort of point i into `point_internode[i]` (the node at the upper end of its internode;
// values < 1 or >= nodes are left out): deterministic and O(points + nodes).
InternodePoints group_by_internode(std::span<const int> point_internode, std::size_t nodes);

}  // namespace treelobes
