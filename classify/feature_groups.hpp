// Internal to classify/: the tree frame shared by the feature groups, the catalogue builder and
// the sink that checks every emitted value against the catalogue. Not part of the public API.
#pragma once

#include "classify/features.hpp"
#include "geometry/kd_tree.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace treelobes::classify::detail {

// One tree in its own frame: origin at the stem foot (axis x = y = 0, ground z = 0), x along
// the crown's major horizontal axis, y along the minor one.
struct TreeFrame {
    std::vector<Eigen::Vector3f> points;  // one point per voxel (cleaned)
    std::vector<Eigen::Vector3f> raw;     // input points, thinned to at most max_raw_points
    std::vector<float> rel_height;        // per voxel point: z / height, clamped to [0, 1]
    std::vector<float> radius;            // per voxel point: horizontal distance to the axis
    float height = 0;                     // metres
    float voxel = 0;                      // voxel size, metres
    float crown_radius = 0;               // 95th percentile of `radius`
    float major_variance = 0, minor_variance = 0;  // variances of x and y (principal axes)
    float trunk_diameter = 0;             // metres; 0 when no stem is visible (shape group sets it)
    float crown_base = 0;                 // metres (shape group sets it)
    std::size_t input_points = 0;         // points of the input cloud (before thinning and cleaning)
    const FeatureOptions* options = nullptr;
    // One neighbour search serves the normals and the skeleton: a kd-tree over `points` and
    // their kNN table (nearest first, at least normal_neighbours and skeleton_table_width wide),
    // read mostly from the cleaning's outlier query.
    std::shared_ptr<const KdTree> index;
    std::shared_ptr<const KnnTable> neighbours;
};

class Catalogue {
public:
    explicit Catalogue(std::vector<FeatureInfo>& list, std::string group) : list_(list), group_(std::move(group)) {}
    void add(std::string name, std::string unit, std::string description) {
        list_.push_back({std::move(name), group_, std::move(unit), std::move(description)});
    }

private:
    std::vector<FeatureInfo>& list_;
    std::string group_;
};

// Appends values in catalogue order; a name that is not the next catalogue entry is a bug
// (Error(Internal)), so code and documentation cannot drift apart.
class FeatureSink {
public:
    explicit FeatureSink(std::vector<double>& values);
    void add(const std::string& name, double value);
    std::size_t size() const { return values_.size(); }

private:
    std::vector<double>& values_;
};

// Feature groups: describe_* adds the catalogue entries, compute_* the values, same order.
void describe_shape(Catalogue& c);
void compute_shape(TreeFrame& frame, FeatureSink& out);  // also sets trunk_diameter, crown_base
void describe_vertical(Catalogue& c);
void compute_vertical(const TreeFrame& frame, FeatureSink& out);
void describe_radial(Catalogue& c);
void compute_radial(const TreeFrame& frame, FeatureSink& out);
void describe_horizontal(Catalogue& c);
void compute_horizontal(const TreeFrame& frame, FeatureSink& out);
void describe_structure(Catalogue& c);
void compute_structure(const TreeFrame& frame, FeatureSink& out);
void describe_normals(Catalogue& c);
void compute_normals(const TreeFrame& frame, FeatureSink& out);
void describe_hull(Catalogue& c);
void compute_hull(const TreeFrame& frame, FeatureSink& out);
void describe_skeleton(Catalogue& c);
void compute_skeleton(const TreeFrame& frame, FeatureSink& out);
void skip_skeleton(FeatureSink& out);  // zeros for every skeleton feature
void describe_envelope(Catalogue& c);
void compute_envelope(const TreeFrame& frame, FeatureSink& out);
void describe_scan(Catalogue& c);
void compute_scan(const TreeFrame& frame, FeatureSink& out);

// Small statistics shared by the groups.
float quantile(std::vector<float> values, double q);  // 0 for an empty vector
struct Moments {
    double mean = 0, sd = 0, m2 = 0, m3 = 0, m4 = 0, skewness = 0, kurtosis = 0;
};
Moments moments(const std::vector<float>& values);
std::string indexed(const std::string& prefix, int index);  // "zhist_07"

}  // namespace treelobes::classify::detail
