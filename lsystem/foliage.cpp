#include "lsystem/foliage.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>

namespace treelobes::lsystem {

std::array<Eigen::Vector3f, 6> leaf_outline(const LeafPlacement& leaf, const LeafShape& shape) {
    const Eigen::Vector3f h = leaf.heading.normalized();
    // L = U x H completes the frame (H x L = U); the blade lies in the plane of H and L.
    const Eigen::Vector3f l = leaf.up.cross(h).normalized();
    const float length = leaf.size;
    const float half = 0.5f * static_cast<float>(shape.width_ratio) * length;
    const Eigen::Vector3f& base = leaf.position;
    return {base,
            base + 0.15f * length * h + 0.6f * half * l,
            base + 0.4f * length * h + half * l,
            base + length * h,
            base + 0.4f * length * h - half * l,
            base + 0.15f * length * h - 0.6f * half * l};
}

TriangleMesh foliage_mesh(std::span<const LeafPlacement> leaves, const LeafShape& shape) {
    TriangleMesh mesh;
    mesh.vertices.reserve(leaves.size() * 6);
    mesh.faces.reserve(leaves.size() * 4);
    for (const LeafPlacement& leaf : leaves) {
        const int v = static_cast<int>(mesh.vertices.size());
        for (const Eigen::Vector3f& p : leaf_outline(leaf, shape)) mesh.vertices.push_back(p);
        // Fan from the base and the tip: (0,1,2) (0,2,3) (0,3,4) (0,4,5).
        for (int k = 1; k <= 4; ++k) mesh.faces.push_back({v, v + k, v + k + 1});
    }
    return mesh;
}

std::size_t FoliageHierarchy::textured_count() const {
    return static_cast<std::size_t>(std::count_if(boxes.begin(), boxes.end(), [](const FoliageBox& b) { return b.textured; }));
}

int FoliageHierarchy::max_depth() const {
    int depth = -1;
    for (const FoliageBox& b : boxes) depth = std::max(depth, b.depth);
    return depth;
}

namespace {

// Per tADT node: the module range of its subtree and the leaves in it. Subtrees are contiguous
// runs of the string (a node's own modules come before its first bracket; see build_tadt).
struct NodeFoliage {
    std::size_t module_end = 0;
    std::size_t leaf_begin = 0, leaf_end = 0;
    std::size_t own_leaves = 0;
    int rep = -1;             // the node whose box this subtree uses; -1 without leaves
    Eigen::AlignedBox3d raw;  // bounds of the subtree's leaf blades
};

void check_leaves(const Tadt& tadt, std::span<const LeafPlacement> leaves) {
    for (std::size_t i = 0; i < leaves.size(); ++i) {
        if (leaves[i].module >= tadt.string.size())
            throw Error::input("foliage", "leaf " + std::to_string(i) + " refers to module " + std::to_string(leaves[i].module) +
                                                  " beyond the string (" + std::to_string(tadt.string.size()) + " modules)");
        if (i > 0 && leaves[i].module <= leaves[i - 1].module)
            throw Error::input("foliage", "leaves are not in string order at leaf " + std::to_string(i) +
                                                  " (interpret the whole string, not a chain prefix)");
    }
}

// Pads a box so that every side is at least `side`, keeping its centre.
Eigen::AlignedBox3d padded(const Eigen::AlignedBox3d& box, double side) {
    Eigen::AlignedBox3d out = box;
    for (int a = 0; a < 3; ++a) {
        const double extent = box.max()[a] - box.min()[a];
        if (extent >= side) continue;
        const double centre = 0.5 * (box.min()[a] + box.max()[a]);
        out.min()[a] = centre - 0.5 * side;
        out.max()[a] = centre + 0.5 * side;
    }
    return out;
}

}  // namespace

FoliageHierarchy build_foliage_hierarchy(const Tadt& tadt, std::span<const LeafPlacement> leaves, const FoliageOptions& options) {
    if (!(options.texture_threshold >= 0.0 && options.texture_threshold < 1.0))
        throw Error::usage("foliage: the texture threshold must be in [0, 1), got " + std::to_string(options.texture_threshold));
    if (!(options.min_side_fraction >= 0.0 && options.min_side_fraction <= 1.0))
        throw Error::usage("foliage: the smallest box side fraction must be in [0, 1]");
    check_leaves(tadt, leaves);

    FoliageHierarchy out;
    out.leaf_count = leaves.size();
    const std::size_t n = tadt.nodes.size();
    out.box_of_node.assign(n, -1);
    if (leaves.empty() || n == 0) return out;

    // Bottom-up (children have larger indices): module ranges, leaf ranges, raw boxes and which
    // node's box each subtree uses.
    std::vector<NodeFoliage> info(n);
    const auto leaf_at_or_after = [&](std::size_t module) {
        return static_cast<std::size_t>(
                std::lower_bound(leaves.begin(), leaves.end(), module, [](const LeafPlacement& l, std::size_t m) { return l.module < m; }) -
                leaves.begin());
    };
    out.ornament.assign(n, 0);
    for (std::size_t i = 1; i < n; ++i) out.ornament[i] = tadt.nodes[i].subtree_length == 0.0;
    for (std::size_t i = n; i-- > 0;) {
        const TadtNode& node = tadt.nodes[i];
        NodeFoliage& f = info[i];
        f.module_end = std::max(f.module_end, node.end);
        for (int c : node.children) f.module_end = std::max(f.module_end, info[static_cast<std::size_t>(c)].module_end);
        const std::size_t begin = i == 0 ? 0 : node.begin;
        f.leaf_begin = leaf_at_or_after(begin);
        f.leaf_end = leaf_at_or_after(std::max(begin, f.module_end));
        const std::size_t own_end = leaf_at_or_after(node.end > node.begin ? node.end : begin);
        for (std::size_t l = f.leaf_begin; l < own_end; ++l)
            for (const Eigen::Vector3f& p : leaf_outline(leaves[l], options.shape)) f.raw.extend(p.cast<double>());
        // Leaves of ornaments count as the node's own; sub-branches with leaves get boxes.
        std::size_t in_branches = 0;
        int leafy_branches = 0, last_leafy = -1;
        for (int c : node.children) {
            const NodeFoliage& child = info[static_cast<std::size_t>(c)];
            f.raw.extend(child.raw);
            if (out.ornament[static_cast<std::size_t>(c)] || child.leaf_end == child.leaf_begin) continue;
            ++leafy_branches;
            last_leafy = c;
            in_branches += child.leaf_end - child.leaf_begin;
        }
        f.own_leaves = f.leaf_end - f.leaf_begin - in_branches;
        if (f.leaf_end == f.leaf_begin || out.ornament[i]) continue;
        // Same foliage as its only leafy sub-branch: share that child's box.
        f.rep = (f.own_leaves == 0 && leafy_branches == 1) ? info[static_cast<std::size_t>(last_leafy)].rep : static_cast<int>(i);
    }

    // Top-down: one box per representative node, parents first.
    const Eigen::AlignedBox3d& root_raw = info[0].raw;
    const double min_side = options.min_side_fraction * (root_raw.max() - root_raw.min()).maxCoeff();
    std::vector<int> box_index(n, -1);
    for (std::size_t i = 0; i < n; ++i) {
        if (info[i].rep != static_cast<int>(i)) continue;
        FoliageBox box;
        box.tadt_node = static_cast<int>(i);
        box.leaf_begin = info[i].leaf_begin;
        box.leaf_end = info[i].leaf_end;
        box.own_leaves = info[i].own_leaves;
        box.box = padded(info[i].raw, min_side);
        // The nearest ancestor with a box of its own (ancestors sharing this box are skipped).
        int a = tadt.nodes[i].parent;
        while (a >= 0 && info[static_cast<std::size_t>(a)].rep == static_cast<int>(i)) a = tadt.nodes[static_cast<std::size_t>(a)].parent;
        if (a >= 0) {
            box.parent = box_index[static_cast<std::size_t>(info[static_cast<std::size_t>(a)].rep)];
            box.depth = out.boxes[static_cast<std::size_t>(box.parent)].depth + 1;
        }
        box_index[i] = static_cast<int>(out.boxes.size());
        if (box.parent >= 0) out.boxes[static_cast<std::size_t>(box.parent)].children.push_back(box_index[i]);
        out.boxes.push_back(std::move(box));
    }
    out.node_leaves.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        out.node_leaves[i] = {info[i].leaf_begin, info[i].leaf_end};
        if (info[i].rep >= 0) out.box_of_node[i] = box_index[static_cast<std::size_t>(info[i].rep)];
    }

    // Padding may let a child stick out of its parent: grow parents bottom-up to keep nesting.
    for (std::size_t b = out.boxes.size(); b-- > 1;) out.boxes[static_cast<std::size_t>(out.boxes[b].parent)].box.extend(out.boxes[b].box);
    const double root_volume = out.boxes[0].box.volume();
    for (FoliageBox& box : out.boxes) {
        box.volume_ratio = root_volume > 0 ? box.box.volume() / root_volume : 1.0;
        box.textured = box.volume_ratio > options.texture_threshold;
    }
    return out;
}

FoliageLod foliage_for_prefix(const Tadt& tadt, const FoliageHierarchy& hierarchy, const std::vector<char>& visited) {
    if (visited.size() != tadt.nodes.size() || hierarchy.box_of_node.size() != tadt.nodes.size())
        throw Error::usage("foliage: visited flags, hierarchy and tADT disagree in size");
    FoliageLod lod;
    if (hierarchy.empty()) return lod;
    for (std::size_t i = 0; i < tadt.nodes.size(); ++i) {
        if (visited[i]) continue;
        const int parent = tadt.nodes[i].parent;
        if (parent >= 0 && !visited[static_cast<std::size_t>(parent)]) continue;  // inside a subtree already counted
        if (parent < 0) {  // nothing visited yet: the root box stands for the whole crown
            lod.textured_boxes.push_back(0);
            lod.leaves_in_textures = hierarchy.leaf_count;
            return lod;
        }
        if (hierarchy.ornament[i]) {
            for (std::size_t l = hierarchy.node_leaves[i].first; l < hierarchy.node_leaves[i].second; ++l) lod.attached_leaves.push_back(l);
            continue;
        }
        const int b = hierarchy.box_of_node[i];
        if (b < 0) continue;
        const FoliageBox& box = hierarchy.boxes[static_cast<std::size_t>(b)];
        if (box.textured) {
            lod.textured_boxes.push_back(b);
            lod.leaves_in_textures += box.leaf_count();
        } else {
            lod.small_boxes.push_back(b);
            lod.leaves_in_small_boxes += box.leaf_count();
        }
    }
    return lod;
}

std::vector<int> foliage_cut(const FoliageHierarchy& hierarchy, int depth) {
    std::vector<int> cut;
    if (hierarchy.empty()) return cut;
    const auto refinable = [&](const FoliageBox& box) {
        if (box.depth >= depth || box.own_leaves > 0 || box.children.empty()) return false;
        return std::all_of(box.children.begin(), box.children.end(),
                           [&](int c) { return hierarchy.boxes[static_cast<std::size_t>(c)].textured; });
    };
    std::vector<int> stack{0};
    while (!stack.empty()) {
        const int b = stack.back();
        stack.pop_back();
        const FoliageBox& box = hierarchy.boxes[static_cast<std::size_t>(b)];
        if (!refinable(box)) {
            cut.push_back(b);
            continue;
        }
        for (auto it = box.children.rbegin(); it != box.children.rend(); ++it) stack.push_back(*it);
    }
    std::sort(cut.begin(), cut.end());
    return cut;
}

std::vector<char> visited_nodes(const MultiresChain& chain, std::size_t end) {
    std::vector<char> visited(chain.tadt.nodes.size(), 0);
    end = std::min(end, chain.entries.size());
    for (std::size_t e = 0; e < end; ++e)
        if (chain.entries[e].kind == ChainEntry::Kind::node) visited[static_cast<std::size_t>(chain.entries[e].node)] = 1;
    return visited;
}

}  // namespace treelobes::lsystem
