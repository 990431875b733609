// Confidence of skeleton edges and the split of a tree into its main branching structure and
// lobe clusters (Livny et al. 2011, §4.2).
//
// Every internode (the edge from a node's parent to the node) has the points the skeleton
// assigned to it. Its confidence measure is the average distance of those points to the edge
// segment; the edge is low-confidence when that average exceeds the branch diameter
// d'(u) = f_s d(u) (Eq. 2). We take d' at the middle of the edge (the mean of both ends):
// allometric diameters fall to 0 at the tips, so d' at the upper end alone would make every
// tip edge low-confidence regardless of its points.
//
// Walking from the root, the first low-confidence edge on a path (from node p_i to its child)
// ends the main branching structure there; the points of that edge and of everything above it
// form cluster C_i, seeded at p_i. Larger f_s -> larger d' -> fewer low-confidence edges, so
// clusters start further out: more, smaller lobes (Livny et al. 2011, Fig. 3/11).
#pragma once

#include "core/tree_graph.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace treelobes::lobes {

struct EdgeConfidence {
    std::vector<float> mean_distance;  // per node (edge parent -> node); 0 for the root and edges without points
    std::vector<int> points;           // points assigned to the edge
    std::vector<float> threshold;      // d' at the middle of the edge
    std::vector<char> low;             // 1 = low confidence (only edges with points can be)
    std::size_t measured_raised = 0;   // edges whose threshold a measured d' raised
    std::size_t low_count() const;
};

// `point_internode[i]` is the node at the upper end of point i's internode, -1 for points the
// skeleton left out; `lobe_diameter` is d'(u) per node. `measured_lobe_diameter` (empty, or one
// per node for the edge parent -> node, 0 = not measured) raises an edge's threshold to it.
// Throws Error(Usage) on size mismatches.
EdgeConfidence edge_confidence(const TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                               std::span<const float> lobe_diameter, std::span<const float> measured_lobe_diameter = {});

// Where the input labels its own wood, as the bark samples of a CG model do (Livny et al. 2011,
// §4: a complete model "will better facilitate the generation of lobe-based representation"),
// an edge's branch diameter is measured instead of only estimated. Eq. 1 stands in for the
// diameters a scan cannot measure; with the γ of Table 1 it gives a tiered terminalia's trunk
// at 14 m 0.16 m against the model's 0.28 m, and the test above then ends the main structure on
// the trunk and makes the whole upper crown one lobe (docs/lobes.md, "Confidence from the wood").
struct WoodMeasurement {
    std::size_t min_points = 3;  // wood points on the edge: fewer measure nothing
    double min_share = 0.9;      // of the edge's points: the edge runs along bark, not twigs among leaves
    double max_factor = 2.0;     // the measured d' raises the mid-edge allometric d' at most this many times:
                                 // wood of several twigs around a crown edge spreads wider than a branch
};

// Throws Error(Usage) unless min_points >= 1, min_share in 0..1 and max_factor >= 1.
void check_wood_measurement(const WoodMeasurement& w);

// Per node, the measured d' of the edge parent -> node: f_s times twice the mean distance of its
// wood points (`wood[i]` != 0) to the edge (bark samples lie one radius from the axis), at most
// max_factor times the mid-edge `lobe_diameter`; 0 where the edge's wood is not measured (above).
std::vector<float> wood_lobe_diameter(const TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                                      std::span<const char> wood, std::span<const float> lobe_diameter, float fs,
                                      const WoodMeasurement& measurement);

struct LobeCluster {
    int seed_node = -1;       // p_i: lower end of the low-confidence edge (on the main structure)
    int first_node = -1;      // upper end of the low-confidence edge: the cluster's subtree root
    std::vector<int> nodes;   // the subtree of first_node, pre-order
    std::vector<int> points;  // indices of the points assigned to those nodes, ascending
};

struct MainSplit {
    std::vector<char> main;             // per node: 1 = main branching structure
    std::vector<LobeCluster> clusters;  // in pre-order of first_node
};

MainSplit split_at_low_confidence(const TreeGraph& tree, const EdgeConfidence& confidence, std::span<const int> point_internode);

}  // namespace treelobes::lobes
