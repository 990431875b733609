#include "segment/tree_labels.hpp"

#include "core/asprs_classes.hpp"

#include <cmath>
#include <unordered_set>

namespace treelobes {

std::vector<std::uint8_t> vegetation_points(const PointCloud& cloud, const Terrain& terrain, float clearance) {
    std::vector<std::uint8_t> keep(cloud.size(), 0);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const bool not_a_tree = !cloud.classification.empty() && asprs_never_a_tree(cloud.classification[i]);
        keep[i] = !not_a_tree && !terrain.is_ground[i] && terrain.height_above_ground[i] >= clearance;
    }
    return keep;
}

OccupiedCells occupied_cells(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation, float cell) {
    std::unordered_set<std::int64_t> cells;
    OccupiedCells occupied;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!vegetation[i]) continue;
        const auto x = static_cast<std::int64_t>(std::floor(cloud.positions[i].x() / cell));
        const auto y = static_cast<std::int64_t>(std::floor(cloud.positions[i].y() / cell));
        cells.insert(x * 2000003 + y);
        ++occupied.points;
    }
    occupied.cells = cells.size();
    return occupied;
}

std::vector<SegmentedTree> collect_trees(const PointCloud& cloud, const Terrain& terrain, std::vector<std::int32_t>& tree_id,
                                         std::size_t labels, const std::vector<Eigen::Vector2f>& stem_xy,
                                         const std::vector<float>& stem_radius, float min_tree_height) {
    std::vector<std::size_t> count(labels + 1, 0);
    std::vector<int> highest(labels + 1, -1);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const auto label = static_cast<std::size_t>(tree_id[i]);
        if (!label) continue;
        ++count[label];
        if (highest[label] < 0 || terrain.height_above_ground[i] > terrain.height_above_ground[static_cast<std::size_t>(highest[label])])
            highest[label] = static_cast<int>(i);
    }
    std::vector<std::int32_t> renumber(labels + 1, 0);
    std::vector<SegmentedTree> trees;
    for (std::size_t label = 1; label <= labels; ++label) {
        if (!count[label] || terrain.height_above_ground[static_cast<std::size_t>(highest[label])] < min_tree_height) continue;
        SegmentedTree tree;
        tree.id = static_cast<std::int32_t>(trees.size() + 1);
        tree.top = cloud.positions[static_cast<std::size_t>(highest[label])];
        const Eigen::Vector2f xy = stem_xy.empty() ? Eigen::Vector2f(tree.top.head<2>()) : stem_xy[label - 1];
        tree.base = Eigen::Vector3f(xy.x(), xy.y(), terrain.dtm.height_at(xy.x(), xy.y()));
        tree.points = count[label];
        tree.stem_radius = stem_radius.empty() ? 0.0f : stem_radius[label - 1];
        renumber[label] = tree.id;
        trees.push_back(tree);
    }
    for (auto& id : tree_id) id = renumber[static_cast<std::size_t>(id)];
    return trees;
}

}  // namespace treelobes
