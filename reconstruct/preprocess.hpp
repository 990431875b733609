// Cleaning a single-tree scan before the skeleton: duplicate removal, optional voxel
// downsampling, statistical outlier removal (global, or local: points much sparser than their
// own neighbours), and removal of the ground when the scan includes it (e.g. treels/pine.las).
// The defaults work on every file of ../shared/data.
#pragma once

#include "core/point_cloud.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace treelobes {

class KdTree;
struct KnnTable;

enum class GroundMode { Auto, Remove, Keep };
// "auto", "remove", "keep"; throws Error(Usage) otherwise.
GroundMode parse_ground_mode(const std::string& text);

// Which outlier test runs (see preprocess.cpp): the global one, the local one, or (Auto) the
// local one on leafy scans only, told by how few points have linear (or planar) neighbourhoods.
enum class OutlierTest { Auto, Global, Local };
// "auto", "global", "local"; throws Error(Usage) otherwise.
OutlierTest parse_outlier_test(const std::string& text);

struct PreprocessOptions {
    float duplicate_distance = 0.0001f;  // metres: points sharing a cell of this size are duplicates (repeated returns)
    float voxel_size = 0.0f;             // metres: keep one point per voxel (0 = off)
    int outlier_neighbours = 8;          // k of the statistical outlier filter (0 = off)
    OutlierTest outlier_test = OutlierTest::Auto;
    float outlier_ratio = 2.0f;           // local test: of the global test's outliers, drop only those whose mean k-NN
                                          // distance exceeds this many times the mean of their neighbours' own
    float outlier_sigma = 3.0f;           // global test: drop points whose mean k-NN distance exceeds
                                          // mean + sigma * stddev over the whole scan
    float leafy_linear_fraction = 0.09f;  // auto: the local test runs when fewer of the points (above the ground)
                                          // than this have a linear neighbourhood of 20 points (and few a planar one)
    GroundMode ground = GroundMode::Auto;
    float ground_tolerance = 0.10f;  // metres above the ground plane still counted as ground
    float ground_min_extent = 1.5f;  // metres: a plane narrower than this (a cut stem) is not ground
    int table_width = 0;             // > 0: also hand on a kd-tree and a kNN table this wide over the kept
                                     // points, mostly read from the outlier filter's (wider) query
};

struct Preprocessed {
    std::vector<Eigen::Vector3f> points;  // kept points (local coordinates of the input)
    std::vector<int> point_of_input;      // per input point: kept point standing for it, -1 if removed
    std::size_t duplicates = 0;           // merged into a kept point (duplicates and voxel mates)
    std::size_t outliers = 0;
    bool local_outlier_test = false;  // the local test ran (else the global one, or none)
    float linear_fraction = -1.0f;    // measured for OutlierTest::Auto (-1: not measured)
    std::size_t ground = 0;
    bool ground_found = false;
    Eigen::Vector4f ground_plane{0, 0, 1, 0};    // n.x n.y n.z d of n.p + d = 0 when ground_found
    std::shared_ptr<const KdTree> index;         // over `points`, when options.table_width > 0
    std::shared_ptr<const KnnTable> neighbours;  // their kNN table, options.table_width wide
};

// Throws Error(InvalidInput) naming `name` when fewer than 10 points are left.
Preprocessed preprocess_cloud(const PointCloud& cloud, const PreprocessOptions& options, const std::string& name = {});

}  // namespace treelobes
