// KdTree: the project's one nearest-neighbour index over 3-D points (FLANN's single kd-tree,
// kept inside geometry/kd_tree.cpp). Construction copies the points, so the index does not
// depend on the lifetime of the caller's vector. Queries are const and thread-safe.
#pragma once

#include <Eigen/Core>

#include <memory>
#include <span>
#include <vector>

namespace treelobes {

struct KnnTable;

class KdTree {
public:
    explicit KdTree(std::span<const Eigen::Vector3f> points);
    ~KdTree();
    KdTree(KdTree&&) noexcept;
    KdTree& operator=(KdTree&&) noexcept;
    KdTree(const KdTree&) = delete;
    KdTree& operator=(const KdTree&) = delete;

    std::size_t size() const;
    const Eigen::Vector3f& point(int index) const;

    // Up to k nearest points, nearest first; distances are squared. Clears the outputs first.
    void knn(const Eigen::Vector3f& query, int k, std::vector<int>& indices, std::vector<float>& squared_distances) const;
    // Every point strictly closer than `radius`, nearest first; at most `max_results` of the
    // nearest when max_results > 0.
    void radius_search(const Eigen::Vector3f& query, float radius, std::vector<int>& indices, std::vector<float>& squared_distances,
                       std::size_t max_results = 0) const;
    // Index of the nearest point (-1 for an empty index).
    int nearest(const Eigen::Vector3f& query, float* squared_distance = nullptr) const;

private:
    friend KnnTable knn_of_all_points(const KdTree& tree, int k);  // reads the index directly
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// A nearest-point index that grows while it is queried (e.g. geometry placed step by step).
// Bentley & Saxe's logarithmic method over static KdTrees: the points form blocks of
// contiguous insertion ranges whose sizes halve from the oldest to the newest, merged like a
// binary counter, so each point is re-indexed O(log n) times and a query visits O(log n)
// blocks; the newest few points are scanned directly.
class GrowingKdTree {
public:
    void add(const Eigen::Vector3f& point);
    std::size_t size() const { return points_.size(); }
    bool empty() const { return points_.empty(); }
    const Eigen::Vector3f& point(int index) const { return points_[static_cast<std::size_t>(index)]; }
    // Index (in order of addition) of the nearest point, -1 when empty. Of points at the same
    // distance in different blocks the earliest added wins.
    int nearest(const Eigen::Vector3f& query) const;

private:
    struct Block {
        std::size_t first;  // insertion index of the block's first point
        KdTree tree;
    };
    std::vector<Eigen::Vector3f> points_;
    std::vector<Block> blocks_;  // oldest (largest) first
    std::size_t indexed_ = 0;    // points_[0, indexed_) are in blocks
};

// k nearest neighbours of every indexed point, the point itself excluded, in rows of k
// (row i = neighbours of point i, nearest first; -1 / +inf pad rows when fewer points exist).
// Runs in parallel (TBB); the result does not depend on the number of threads.
struct KnnTable {
    int k = 0;
    std::vector<int> indices;
    std::vector<float> squared_distances;
    const int* row(std::size_t i) const { return indices.data() + i * static_cast<std::size_t>(k); }
    const float* row_distances(std::size_t i) const { return squared_distances.data() + i * static_cast<std::size_t>(k); }
};
KnnTable knn_of_all_points(const KdTree& tree, int k);

}  // namespace treelobes
