// Skeleton extraction from a single-tree point cloud (Livny et al. 2011, §4.1, after Xu et al. 2007 and
// Livny et al. 2010):
//   1. neighbour graph with edge weights ||u-v||^beta (geometry/neighbour_graph.hpp); a
//      piece cut off by an occlusion gap is bridged where its own axis leads, not sideways to
//      the nearest bark (the straight join the skeleton draws across the gap follows the bridge);
//   2. stem foot (reconstruct/tree_base.hpp) and two multi-source Dijkstra runs from its
//      points: one over the weights ||u-v||^beta (the shortest-path tree of the paper) and one
//      over Euclidean lengths (the geodesic distance, a smooth field: paths of the weighted
//      tree zigzag, and their lengths would cut one cross-section into several bins);
//   3. points are cut into geodesic bins of width w (a finer width on thin branches, measured
//      from a first slicing at w) and each bin into connected clusters of nearby points; a
//      cluster hangs from the lower-bin cluster that most weighted-tree edges enter it from, so
//      the clusters form one rooted tree shaped by beta; fragments of one cross-section merge;
//      wide slices are centred on a fitted circle (one-sided scans), and slices of a thick stem
//      whose axis is known below on a circle fitted to a slab cut across that axis (where the
//      geodesic distance winds around a sparse stem, a bin is an arc of the bark, not a ring);
//   4. leaf chains shorter than the twig length are pruned, chains are smoothed and resampled
//      to near-uniform internodes of length l;
//   5. the children of every node are ordered main (largest subtree) first and nodes are
//      numbered in pre-order, so vertex 0 is the root.
// Every point keeps the internode it belongs to: the index of the node at the internode's
// upper end (the root's points go to the root's main child).
#pragma once

#include "core/point_cloud.hpp"
#include "core/tree_graph.hpp"
#include "reconstruct/tree_base.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace treelobes {

class KdTree;
struct KnnTable;

struct SkeletonOptions {
    int neighbours = 10;            // k of the neighbour graph
    double beta = 1.5;              // edge weight exponent (species library; 1.5 without species)
    float max_edge_length = 0.0f;   // metres; longer kNN edges are replaced by bridges (0 = 10 x spacing)
    float bin_width = 0.0f;         // metres; geodesic bin width (0 = 2.5 x the sampling distance, kept within 0.02..0.5)
    float fine_bin_factor = 0.64f;  // thin branches are binned at this fraction of the bin width (1 = one width everywhere)
    float thick_slice = 0.55f;      // bin widths; a slice at least this thick (sqrt of its middle covariance
                                    // eigenvalue) keeps the full bin width, and so do the two slices above it
    float internode_length = 0.0f;  // metres; output internode length (0 = the bin width)
    float min_twig_length = 0.0f;   // metres; leaf chains shorter than this are pruned (0 = 2 bins)
    float merge_distance = 0.0f;    // metres; sibling clusters of one bin closer than this merge (0 = 1 bin)
    int smoothing_iterations = 1;   // Laplacian passes over each chain (0 = none)
    int geodesic_smoothing = 3;     // neighbour-averaging passes over the geodesic field before binning
    bool fit_axes = true;           // move wide clusters onto a fitted circle centre (one-sided scans)
    float bridge_direction = 2.0f;  // weight of the angle between a gap bridge and its piece's axis (0 = shortest bridges)
    float max_gap = 0.0f;           // metres; parts reached only across a longer gap stay out of the skeleton (0 = keep all)
    int max_gap_points = 0;         // with max_gap: only parts of fewer points stay out, bigger ones keep their join (0 = any size)
    TreeBaseOptions base;
};

struct SkeletonResult {
    TreeGraph tree;                     // radii are 0: reconstruct/allometry.hpp sets them
    std::vector<int> point_internode;   // per input point: node at the upper end of its internode
    std::vector<float> point_geodesic;  // per input point: geodesic distance from the stem foot (metres)
    // Per node: placed on a branch axis measured by a trusted circle or slab fit (with the node
    // below it). Such a node's internode may hold only a patch of one side's bark (sparse or
    // one-sided scans of thick stems), so later re-centring on those points must leave it.
    std::vector<bool> node_on_axis;
    TreeBase base;
    float spacing = 0.0f;  // median nearest-neighbour distance (metres)
    float bin_width = 0.0f;
    float internode_length = 0.0f;
    std::size_t clusters = 0;          // bin clusters after merging fragments
    std::size_t pruned_nodes = 0;      // clusters removed as spurious twigs
    std::size_t detached_points = 0;   // points beyond a gap > max_gap, assigned to the internode they hang from
    std::size_t graph_components = 0;  // pieces of the neighbour graph before bridging
    std::size_t bridges = 0;
    float longest_bridge = 0.0f;
};

// Throws Error(InvalidInput) naming `name` for fewer than 10 points or non-finite coordinates,
// Error(Usage) for options out of range.
// `index` (a kd-tree over exactly these points) and `near` (their kNN table, skeleton_table_width
// wide) may be passed when the caller has them already (preprocess_cloud does); they are built
// here otherwise.
SkeletonResult reconstruct_skeleton(std::span<const Eigen::Vector3f> points, const SkeletonOptions& options, const std::string& name = {},
                                    const KdTree* index = nullptr, const KnnTable* near = nullptr);

// Width of the kNN table the skeleton works from: it serves the graph, the bridges, the
// sampling distance and the joining of bin clusters.
inline int skeleton_table_width(const SkeletonOptions& options) { return options.neighbours > 20 ? options.neighbours : 20; }

// The skeleton of a cloud as it is (no cleaning); the tree takes the cloud's origin.
TreeGraph extract_skeleton(const PointCloud& cloud, const SkeletonOptions& options = {});

}  // namespace treelobes
