#include "geometry/kd_tree.hpp"

#include "core/parallel.hpp"

#include <flann/flann.hpp>

#include <algorithm>
#include <limits>

namespace treelobes {

// Single kd-tree (exact search) with leaves of 10 points: the fastest FLANN index for 3-D data.
struct KdTree::Impl {
    std::vector<Eigen::Vector3f> points;
    std::unique_ptr<flann::KDTreeSingleIndex<flann::L2_Simple<float>>> index;
    flann::SearchParams params;

    explicit Impl(std::span<const Eigen::Vector3f> source) : points(source.begin(), source.end()) {
        params.checks = flann::FLANN_CHECKS_UNLIMITED;
        params.eps = 0.0f;
        params.sorted = true;
        if (points.empty()) return;
        // Eigen::Vector3f is three packed floats, so the vector is a row-major n x 3 matrix.
        static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
        flann::Matrix<float> data(points.front().data(), points.size(), 3);
        index = std::make_unique<flann::KDTreeSingleIndex<flann::L2_Simple<float>>>(data, flann::KDTreeSingleIndexParams(10));
        index->buildIndex();
    }
};

KdTree::KdTree(std::span<const Eigen::Vector3f> points) : impl_(std::make_unique<Impl>(points)) {}
KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

std::size_t KdTree::size() const { return impl_->points.size(); }
const Eigen::Vector3f& KdTree::point(int index) const { return impl_->points[static_cast<std::size_t>(index)]; }

void KdTree::knn(const Eigen::Vector3f& query, int k, std::vector<int>& indices, std::vector<float>& squared_distances) const {
    indices.clear();
    squared_distances.clear();
    if (!impl_->index || k <= 0) return;
    const std::size_t capacity = std::min<std::size_t>(static_cast<std::size_t>(k), size());
    flann::KNNSimpleResultSet<float> result(capacity);
    impl_->index->findNeighbors(result, query.data(), impl_->params);
    std::vector<std::size_t> found(result.size());
    squared_distances.resize(result.size());
    result.copy(found.data(), squared_distances.data(), found.size());
    indices.assign(found.begin(), found.end());
}

void KdTree::radius_search(const Eigen::Vector3f& query, float radius, std::vector<int>& indices, std::vector<float>& squared_distances,
                           std::size_t max_results) const {
    indices.clear();
    squared_distances.clear();
    if (!impl_->index || !(radius > 0.0f)) return;
    std::vector<std::size_t> found;
    const float r2 = radius * radius;
    if (max_results > 0) {
        flann::KNNRadiusResultSet<float> result(r2, max_results);
        impl_->index->findNeighbors(result, query.data(), impl_->params);
        found.resize(result.size());
        squared_distances.resize(result.size());
        result.copy(found.data(), squared_distances.data(), found.size(), true);
    } else {
        flann::RadiusResultSet<float> result(r2);
        impl_->index->findNeighbors(result, query.data(), impl_->params);
        found.resize(result.size());
        squared_distances.resize(result.size());
        result.copy(found.data(), squared_distances.data(), found.size(), true);
    }
    indices.assign(found.begin(), found.end());
}

int KdTree::nearest(const Eigen::Vector3f& query, float* squared_distance) const {
    if (!impl_->index) return -1;
    flann::KNNSimpleResultSet<float> result(1);
    impl_->index->findNeighbors(result, query.data(), impl_->params);
    std::size_t index = 0;
    float distance = 0;
    result.copy(&index, &distance, 1);
    if (squared_distance) *squared_distance = distance;
    return static_cast<int>(index);
}

namespace {
constexpr std::size_t kUnindexedTail = 32;  // newest points scanned directly: cheaper than a tiny index
}

void GrowingKdTree::add(const Eigen::Vector3f& point) {
    points_.push_back(point);
    if (points_.size() - indexed_ < kUnindexedTail) return;
    // The tail becomes the newest block; blocks no bigger than it merge into it.
    std::size_t first = indexed_;
    while (!blocks_.empty() && blocks_.back().tree.size() <= points_.size() - first) {
        first = blocks_.back().first;
        blocks_.pop_back();
    }
    const std::span<const Eigen::Vector3f> range(points_.data() + first, points_.size() - first);
    blocks_.push_back({first, KdTree(range)});
    indexed_ = points_.size();
}

int GrowingKdTree::nearest(const Eigen::Vector3f& query) const {
    int best = -1;
    float best_d2 = std::numeric_limits<float>::infinity();
    // Candidates arrive in order of addition, so a strict comparison keeps the earliest of ties.
    auto consider = [&](std::size_t i) {
        const float d2 = (points_[i] - query).squaredNorm();
        if (d2 < best_d2) {
            best_d2 = d2;
            best = static_cast<int>(i);
        }
    };
    for (const Block& block : blocks_) consider(block.first + static_cast<std::size_t>(block.tree.nearest(query)));
    for (std::size_t i = indexed_; i < points_.size(); ++i) consider(i);
    return best;
}

KnnTable knn_of_all_points(const KdTree& tree, int k) {
    KnnTable table;
    table.k = k;
    const std::size_t n = tree.size();
    table.indices.assign(n * static_cast<std::size_t>(k), -1);
    table.squared_distances.assign(n * static_cast<std::size_t>(k), std::numeric_limits<float>::infinity());
    if (!tree.impl_->index || k <= 0) return table;
    const auto& index = *tree.impl_->index;
    const std::size_t capacity = std::min<std::size_t>(static_cast<std::size_t>(k) + 1, n);
    treelobes::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
        // One result set and buffer per block: the same search as knn(), without two
        // allocations per query.
        flann::KNNSimpleResultSet<float> result(capacity);
        std::vector<std::size_t> found(capacity);
        std::vector<float> d2(capacity);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            result.clear();
            index.findNeighbors(result, tree.impl_->points[i].data(), tree.impl_->params);
            const std::size_t count = result.size();
            result.copy(found.data(), d2.data(), count);
            int* row = table.indices.data() + i * static_cast<std::size_t>(k);
            float* row_d = table.squared_distances.data() + i * static_cast<std::size_t>(k);
            int filled = 0;
            for (std::size_t j = 0; j < count && filled < k; ++j) {
                if (found[j] == i) continue;  // the point itself
                row[filled] = static_cast<int>(found[j]);
                row_d[filled] = d2[j];
                ++filled;
            }
        }
    });
    return table;
}

}  // namespace treelobes
