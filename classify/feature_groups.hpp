// Internal to classify/: the tree frame shared by the feature groups, the catalogue builder and
// the sink that checks every emitted value against the catalogue. Not part of the public API.
#pragma once

#include "classify/features.hpp"
#include "geometry/kd_tree.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace treelobes::classify::detail {

// One tree in its own frame: origin at the stem foot (axis x = y = 0, ground z = 0), x along
// the crown's major horizontal axis, y along the minor one.
struct TreeFrame {
    std::vector<Eigen::Vector3f> points;           // one point per voxel (cleaned)
    std::vector<Eigen::Vector3f> raw;              // input points, thinned to at most max_raw_points
    std::vector<float> rel_height;                 // per voxel point: z / height, clamped to [0, 1]
    std::vector<float> radius;                     // per voxel point: horizontal distance to the axis
    float height = 0;                              // metres
    float voxel = 0;                               // voxel size, metres
    float crown_radius = 0;                        // 95th percentile of `radius`
    float major_variance = 0, minor_variance = 0;  // variances of x and y (principal axes)
    float trunk_diameter = 0;                      // metres; 0 when no stem is visible (shape group sets it)
    float crown_base = 0;                          // metres (shape group sets it)
    std::size_t input_points = 0;                  // points of the input cloud (before thinning and cleaning)
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
    // A value that cannot be computed for this tree (too few points, no intensity, ...): NaN,
    // which the classifiers treat as missing.
    void missing(const std::string& name);
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
// input_points per m^2 of the crown disc of radius crown_radius.
void compute_scan(std::size_t input_points, float crown_radius, FeatureSink& out);

// The airborne group reads the crown with its attributes (intensity, returns, colours) and the
// clip's ground returns: computed for every tree, however few points it has.
struct AirborneInput {
    const PointCloud* crown = nullptr;  // the crown, or `thinned` (see airborne_input in features.cpp)
    std::shared_ptr<const PointCloud> thinned;
    std::optional<float> ground_z;  // lowest ground return, when the clip has ground returns
    std::size_t ground_returns = 0;
    double ground_intensity = 0;  // median intensity of the ground returns (0: none)
};
void describe_airborne(Catalogue& c);
void compute_airborne(const AirborneInput& in, FeatureSink& out);
// The group's crown radius (als_crown_radius): the scan density of trees too small for the frame.
float airborne_crown_radius(const AirborneInput& in);

// Small statistics shared by the groups.
float quantile(std::vector<float> values, double q);  // 0 for an empty vector
struct Moments {
    double mean = 0, sd = 0, m2 = 0, m3 = 0, m4 = 0, skewness = 0, kurtosis = 0;
};
Moments moments(const std::vector<float>& values);
std::string indexed(const std::string& prefix, int index);  // "zhist_07"

}  // namespace treelobes::classify::detail
