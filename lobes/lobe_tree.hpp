// The lobe-based tree representation of Livny et al. 2011, §4-5: the main branching structure (a
// skeletal graph with allometric diameters), one closed lobe surface per low-confidence
// cluster with its seed point, and the species parameters needed to synthesize the tree again.
// build_lobe_tree() derives it from a skeleton reconstruction (reconstruct/reconstruct_tree.hpp);
// lobes/tlobe_io.hpp stores it.
#pragma once

#include "core/point_cloud.hpp"
#include "core/tree_graph.hpp"
#include "core/triangle_mesh.hpp"
#include "geometry/alpha_shape.hpp"
#include "lobes/lobe_split.hpp"
#include "lobes/occupancy.hpp"
#include "reconstruct/reconstruct_tree.hpp"

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace treelobes::lobes {

struct Lobe {
    TriangleMesh mesh;                            // closed 2-manifold, outward, in the tree's frame (origin 0)
    int seed_node = -1;                           // p_i as a node of LobeTree::skeleton
    Eigen::Vector3f seed_direction{0, 0, 1};      // unit vector from p_i toward the cluster's centroid
    std::size_t points = 0;                       // points of cluster C_i
    std::vector<Eigen::Vector3f> cluster_points;  // C_i in the tree's frame, plus the nearby points the
                                                  // reconstruction dropped as outliers; not stored: the .tlobe
                                                  // keeps their occupancy, on a grid sized to the file budget
    Occupancy occupancy;                          // read from a .tlobe (empty when the file had no room for it)
    // Share of cluster C_i's points that lie on leaves, when the input labels wood and leaves
    // (LobeOptions::leaf_label_attribute); -1 = unknown. Synthesis draws a
    // lobe's leaves in proportion to it, so that bare twigs stay bare.
    float leaf_share = -1.0f;
    // The file stores no surface for this lobe: it is derived from the occupancy
    // (surface_of_occupancy in lobes/occupancy.hpp), what the .tlobe writer does where the
    // budget binds (docs/tlobe.md, version 6.0). `mesh` then holds the derived surface.
    bool surface_from_occupancy = false;
    double volume() const { return mesh.signed_volume(); }
    double area() const { return mesh.area(); }
};

struct LobeTree {
    TreeGraph skeleton;                        // main branching structure; radius = d(u)/2 (Livny et al. 2011, Eq. 1)
    std::string species;                       // may be empty (no species given)
    double beta = 1.5, gamma = 1.5, fs = 1.0;  // Livny et al. 2011, Table 1 parameters used
    double alpha_factor = 5.0;
    double root_diameter = 0.0;  // d_root (metres)
    // The tree's one-sided leaf area (m^2) when it is known, 0 when not: `treelobes rebuild`
    // stores the original mesh's, and synthesis then sizes the leaf blades to give it back.
    double leaf_area_m2 = 0.0;
    std::vector<Lobe> lobes;

    // Seed point p_i of a lobe: position, thickness (d at p_i) and direction.
    Eigen::Vector3f seed_position(const Lobe& lobe) const { return skeleton.nodes[lobe.seed_node].position; }
    float seed_thickness(const Lobe& lobe) const { return 2.0f * skeleton.nodes[lobe.seed_node].radius; }
};

struct LobeOptions {
    AlphaShapeOptions alpha;              // alpha = alpha_factor * alpha_min (default 5)
    std::size_t min_cluster_points = 30;  // smaller clusters stay on the skeleton as branches
    std::size_t max_shape_points = 6000;  // larger clusters are thinned on a grid before the alpha shape
    std::size_t face_budget = 12000;      // faces over all lobes after simplification, shared by area
    std::size_t max_lobe_faces = 600;     // per lobe, at most
    std::size_t min_lobe_faces = 12;      // per lobe, at least (when the alpha shape has more)
    double simplify_tolerance = 0.02;     // metres: collapses below this error always happen
    double dropped_point_reach = 0.0;     // metres: outliers this close to a cluster join its occupancy (0 = off:
                                          // the larger occupancy takes coarser cells, docs/lobes.md)
    // Per-point attribute of the input's own wood/leaf labels (0 = leaf), from which each lobe
    // records its leaf share; empty = none. `treelobes rebuild` names the labels of the mesh's
    // materials; a synthetic scan's `wood` attribute is the generator's truth and is not used.
    std::string leaf_label_attribute;
    // With those labels, the confidence diameter d' of an edge along bark is raised to what its
    // wood points measure (lobes/lobe_split.hpp).
    WoodMeasurement wood_measurement;
};

struct LobeReport {
    std::size_t low_confidence_edges = 0;
    std::size_t wood_measured_edges = 0;      // edges whose d' the input's wood labels raised
    std::size_t clusters = 0;                 // before the fallbacks below
    std::size_t kept_small = 0;               // clusters under min_cluster_points kept as branches
    std::size_t kept_no_shape = 0;            // clusters without a 3D alpha shape (flat, collinear) kept as branches
    std::size_t lobe_points = 0;              // points inside lobes
    std::size_t main_points = 0;              // points on the main structure
    std::size_t dropped_points_attached = 0;  // outliers added to lobes' occupancy points
    std::size_t faces_before_simplification = 0;
    std::vector<std::pair<std::string, double>> seconds;
};

// `cloud` is the cloud `reconstruction` was made from (its point_internode indexes it).
// `species` and the parameters in `reconstruction_options` are recorded in the result.
LobeTree build_lobe_tree(const PointCloud& cloud, const TreeReconstruction& reconstruction,
                         const ReconstructOptions& reconstruction_options, const std::string& species, const LobeOptions& options = {},
                         LobeReport* report = nullptr);

}  // namespace treelobes::lobes
