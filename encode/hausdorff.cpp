#include "encode/hausdorff.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace treelobes::encode {

namespace {

struct Segment {
    Eigen::Vector3d a, b;
};

Eigen::Vector3d world(const TreeGraph& tree, int node) { return tree.nodes[node].position.cast<double>() + tree.origin; }

// Every edge as a segment; a tree without edges is its root point.
std::vector<Segment> segments_of(const TreeGraph& tree) {
    std::vector<Segment> segments;
    for (std::size_t i = 1; i < tree.size(); ++i) segments.push_back({world(tree, tree.nodes[i].parent), world(tree, static_cast<int>(i))});
    if (segments.empty() && !tree.empty()) segments.push_back({world(tree, 0), world(tree, 0)});
    return segments;
}

// The root and points at most `step` apart along every edge (edge end points included).
std::vector<Eigen::Vector3d> samples_of(const TreeGraph& tree, double step) {
    std::vector<Eigen::Vector3d> samples;
    if (tree.empty()) return samples;
    samples.push_back(world(tree, 0));
    for (std::size_t i = 1; i < tree.size(); ++i) {
        const Eigen::Vector3d a = world(tree, tree.nodes[i].parent), b = world(tree, static_cast<int>(i));
        const auto pieces = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil((b - a).norm() / step)));
        for (std::size_t k = 1; k <= pieces; ++k) samples.push_back(a + (b - a) * (static_cast<double>(k) / pieces));
    }
    return samples;
}

double distance_to_segment(const Eigen::Vector3d& p, const Segment& s) {
    const Eigen::Vector3d ab = s.b - s.a;
    const double length2 = ab.squaredNorm();
    const double t = length2 > 0.0 ? std::clamp((p - s.a).dot(ab) / length2, 0.0, 1.0) : 0.0;
    return (p - (s.a + t * ab)).norm();
}

// Uniform grid over segments for nearest-segment queries: cells hold the segments whose
// bounding box overlaps them; a query searches cubic shells of cells around the query point
// until no unvisited cell can hold a closer segment.
class SegmentGrid {
public:
    explicit SegmentGrid(std::vector<Segment> segments) : segments_(std::move(segments)), stamp_(segments_.size(), 0) {
        Eigen::Vector3d lo = segments_[0].a, hi = segments_[0].a;
        double total_length = 0.0;
        for (const Segment& s : segments_) {
            lo = lo.cwiseMin(s.a).cwiseMin(s.b);
            hi = hi.cwiseMax(s.a).cwiseMax(s.b);
            total_length += (s.b - s.a).norm();
        }
        // Cells about one edge long; coarser when that would make too many cells.
        const Eigen::Vector3d extent = (hi - lo).cwiseMax(1e-9);
        cell_ = std::max(total_length / segments_.size(), extent.maxCoeff() / 1024.0);
        while ((extent / cell_).array().floor().prod() > 1.0e6) cell_ *= 2.0;
        min_ = lo;
        for (int axis = 0; axis < 3; ++axis) dims_[axis] = static_cast<long>(extent[axis] / cell_) + 1;
        fill_cells();
    }

    double nearest(const Eigen::Vector3d& p) {
        ++query_;
        long c[3];
        long start = 0;
        for (int axis = 0; axis < 3; ++axis) {
            c[axis] = static_cast<long>(std::floor((p[axis] - min_[axis]) / cell_));
            start = std::max({start, -c[axis], c[axis] - (dims_[axis] - 1)});  // first shell that meets the grid
        }
        double best = std::numeric_limits<double>::infinity();
        for (long k = start;; ++k) {
            visit_shell(c, k, p, best);
            // Cells of shell k+1 are at least k cells away from any point of the centre cell.
            if (best <= static_cast<double>(k) * cell_ || covers_grid(c, k)) return best;
        }
    }

private:
    long cell_index(long x, long y, long z) const { return (z * dims_[1] + y) * dims_[0] + x; }

    long clamp_axis(double value, int axis) const {
        return std::clamp(static_cast<long>(std::floor((value - min_[axis]) / cell_)), 0L, dims_[axis] - 1);
    }

    // Compressed rows: offsets_[cell]..offsets_[cell + 1] index into entries_.
    void fill_cells() {
        const long cells = dims_[0] * dims_[1] * dims_[2];
        offsets_.assign(static_cast<std::size_t>(cells) + 1, 0);
        for (int pass = 0; pass < 2; ++pass) {
            std::vector<std::size_t> cursor;
            if (pass == 1) {
                for (long i = 0; i < cells; ++i) offsets_[i + 1] += offsets_[i];
                entries_.resize(offsets_.back());
                cursor.assign(offsets_.begin(), offsets_.end() - 1);
            }
            for (std::size_t s = 0; s < segments_.size(); ++s) {
                const Eigen::Vector3d lo = segments_[s].a.cwiseMin(segments_[s].b), hi = segments_[s].a.cwiseMax(segments_[s].b);
                for (long z = clamp_axis(lo[2], 2); z <= clamp_axis(hi[2], 2); ++z)
                    for (long y = clamp_axis(lo[1], 1); y <= clamp_axis(hi[1], 1); ++y)
                        for (long x = clamp_axis(lo[0], 0); x <= clamp_axis(hi[0], 0); ++x) {
                            const long cell = cell_index(x, y, z);
                            if (pass == 0)
                                ++offsets_[cell + 1];
                            else
                                entries_[cursor[cell]++] = static_cast<int>(s);
                        }
            }
        }
    }

    // Visits the cells at Chebyshev distance exactly k from cell c that lie inside the grid.
    void visit_shell(const long c[3], long k, const Eigen::Vector3d& p, double& best) {
        for (long z = std::max(0L, c[2] - k); z <= std::min(dims_[2] - 1, c[2] + k); ++z)
            for (long y = std::max(0L, c[1] - k); y <= std::min(dims_[1] - 1, c[1] + k); ++y) {
                const bool face = std::abs(z - c[2]) == k || std::abs(y - c[1]) == k;
                // Inside the shell's faces in z and y only the two x ends belong to the shell.
                const long step = face || k == 0 ? 1 : 2 * k;
                for (long x = c[0] - k; x <= c[0] + k; x += step) {
                    if (x < 0 || x >= dims_[0]) continue;
                    visit_cell(cell_index(x, y, z), p, best);
                }
            }
    }

    void visit_cell(long cell, const Eigen::Vector3d& p, double& best) {
        for (std::size_t e = offsets_[cell]; e < offsets_[cell + 1]; ++e) {
            const int s = entries_[e];
            if (stamp_[s] == query_) continue;
            stamp_[s] = query_;
            best = std::min(best, distance_to_segment(p, segments_[s]));
        }
    }

    bool covers_grid(const long c[3], long k) const {
        for (int axis = 0; axis < 3; ++axis)
            if (c[axis] - k > 0 || c[axis] + k < dims_[axis] - 1) return false;
        return true;
    }

    std::vector<Segment> segments_;
    std::vector<std::uint64_t> stamp_;  // query that last measured each segment (no double work)
    std::uint64_t query_ = 0;
    Eigen::Vector3d min_;
    double cell_ = 1.0;
    long dims_[3] = {1, 1, 1};
    std::vector<std::size_t> offsets_;
    std::vector<int> entries_;
};

struct Directed {
    double max = 0.0;
    double mean = 0.0;
};

Directed directed_distance(const std::vector<Eigen::Vector3d>& samples, SegmentGrid& target) {
    Directed d;
    for (const Eigen::Vector3d& p : samples) {
        const double distance = target.nearest(p);
        d.max = std::max(d.max, distance);
        d.mean += distance;
    }
    if (!samples.empty()) d.mean /= static_cast<double>(samples.size());
    return d;
}

double bounding_box_diagonal(const TreeGraph& tree) {
    Eigen::Vector3d lo = world(tree, 0), hi = lo;
    for (std::size_t i = 1; i < tree.size(); ++i) {
        lo = lo.cwiseMin(world(tree, static_cast<int>(i)));
        hi = hi.cwiseMax(world(tree, static_cast<int>(i)));
    }
    return (hi - lo).norm();
}

}  // namespace

HausdorffResult skeleton_hausdorff(const TreeGraph& original, const TreeGraph& other, const HausdorffOptions& options) {
    if (original.empty() || other.empty()) throw Error(ExitCode::Internal, "skeleton_hausdorff: empty tree");
    HausdorffResult result;
    result.diagonal = bounding_box_diagonal(original);
    double step = options.sample_step > 0.0 ? options.sample_step : result.diagonal / 1000.0;
    if (!(step > 0.0)) step = 1.0;  // a single point: any step samples it

    SegmentGrid original_grid(segments_of(original)), other_grid(segments_of(other));
    const auto original_samples = samples_of(original, step), other_samples = samples_of(other, step);
    const Directed forward = directed_distance(original_samples, other_grid);
    const Directed backward = directed_distance(other_samples, original_grid);

    result.forward_max = forward.max;
    result.forward_mean = forward.mean;
    result.backward_max = backward.max;
    result.backward_mean = backward.mean;
    result.max = std::max(forward.max, backward.max);
    result.mean = 0.5 * (forward.mean + backward.mean);
    result.samples = original_samples.size() + other_samples.size();
    if (result.diagonal > 0.0) {
        result.max_normalised = result.max / result.diagonal;
        result.mean_normalised = result.mean / result.diagonal;
    }
    return result;
}

VertexErrorCheck check_vertex_error(const TreeGraph& original, const TreeGraph& decoded, const std::vector<int>& decoded_to_source,
                                    double voxel_size) {
    if (decoded_to_source.size() != decoded.size())
        throw Error(ExitCode::Internal, "check_vertex_error: the node map does not match the decoded tree");
    VertexErrorCheck check;
    check.bound = std::sqrt(3.0) * voxel_size / 2.0;
    for (std::size_t k = 0; k < decoded.size(); ++k) {
        const Eigen::Vector3d source = world(original, decoded_to_source[k]);
        const double error = (world(decoded, static_cast<int>(k)) - source).norm();
        check.max_error = std::max(check.max_error, error);
        if (error > check.bound + 1e-6 * (1.0 + source.norm())) check.within_bound = false;
    }
    return check;
}

}  // namespace treelobes::encode
