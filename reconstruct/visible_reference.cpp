#include "reconstruct/visible_reference.hpp"

#include "core/error.hpp"

#include <vector>

namespace treelobes {

SkeletonGraph visible_reference(const SkeletonGraph& reference, std::span<const double> point_internode, std::size_t min_points) {
    if (!reference.tree)
        throw Error::usage("the visible part of a reference needs a reference skeleton that is one tree rooted at vertex 0");
    const TreeGraph& tree = *reference.tree;
    std::vector<std::size_t> hits(tree.size(), 0);
    for (double v : point_internode)
        if (v >= 0 && v < static_cast<double>(tree.size())) ++hits[static_cast<std::size_t>(v)];
    std::vector<bool> keep(tree.size(), false);
    bool any = false;
    for (std::size_t i = 1; i < tree.size(); ++i) {
        if (hits[i] < min_points) continue;
        any = true;
        for (int v = static_cast<int>(i); v >= 0 && !keep[static_cast<std::size_t>(v)]; v = tree.nodes[v].parent)
            keep[static_cast<std::size_t>(v)] = true;
    }
    if (!any) throw Error::input("visible reference", "no internode of the reference holds " + std::to_string(min_points) + " scan points");

    SkeletonGraph visible;
    visible.kind = reference.kind;
    TreeGraph kept;
    kept.origin = tree.origin;
    std::vector<int> index(tree.size(), -1);
    for (int v : tree.preorder()) {  // pre-order keeps the main child first
        if (!keep[static_cast<std::size_t>(v)]) continue;
        const int parent = tree.nodes[v].parent;
        index[v] = kept.add_node(tree.nodes[v].position, tree.nodes[v].radius, parent < 0 ? -1 : index[parent]);
    }
    for (std::size_t i = 0; i < kept.size(); ++i) {
        visible.vertices.push_back(kept.origin + kept.nodes[i].position.cast<double>());
        visible.radius.push_back(kept.nodes[i].radius);
        if (kept.nodes[i].parent >= 0) visible.edges.emplace_back(kept.nodes[i].parent, static_cast<int>(i));
    }
    visible.stem = reference.stem;  // the trunk is on every seen internode's way to the root
    visible.tree = std::move(kept);
    return visible;
}

SkeletonComparison compare_with_visible_part(const SkeletonGraph& skeleton, const SkeletonGraph& reference,
                                             std::span<const double> point_internode, std::size_t min_points, const EvalOptions& options) {
    SkeletonComparison seen = compare_skeletons(skeleton, visible_reference(reference, point_internode, min_points), options);
    if (min_points <= 1) return seen;
    SkeletonComparison touched = compare_skeletons(skeleton, visible_reference(reference, point_internode, 1), options);
    seen.touched_reference_length = touched.reference_length;
    seen.to_reference = touched.to_reference;
    seen.sample_positions = std::move(touched.sample_positions);
    seen.sample_distances = std::move(touched.sample_distances);
    if (seen.branches && touched.branches) {
        seen.branches->skeleton_branches = touched.branches->skeleton_branches;
        seen.branches->correct = touched.branches->correct;
        seen.branches->precision = touched.branches->precision;
    }
    return seen;
}

}  // namespace treelobes
