// Error metrics between an original skeleton and a decoded (or LOD-reduced) one (Strnad et al. 2020
// Fig. 5 and 8): Hausdorff distances between the skeletons as polylines, sampled along the
// edges and normalised by the original's bounding-box diagonal, and the per-vertex bound
// √3·d/2 of voxel-centre decoding (§3.1).
#pragma once

#include "core/tree_graph.hpp"

#include <cstddef>
#include <vector>

namespace treelobes::encode {

struct HausdorffOptions {
    double sample_step = 0.0;  // metres between samples on an edge; 0 = 1/1000 of the original's diagonal
};

struct HausdorffResult {
    double forward_max = 0.0;  // original -> other: farthest original sample from the other skeleton
    double forward_mean = 0.0;
    double backward_max = 0.0;  // other -> original
    double backward_mean = 0.0;
    double max = 0.0;             // symmetric Hausdorff distance: max of both directions (metres)
    double mean = 0.0;            // mean of the two directed means (metres)
    double diagonal = 0.0;        // bounding-box diagonal of the original's vertices (metres)
    double max_normalised = 0.0;  // max / diagonal (0 when the diagonal is 0)
    double mean_normalised = 0.0;
    std::size_t samples = 0;  // points sampled on both skeletons
};

// Distances between the skeletons as sets of segments; positions are compared in original
// coordinates (position + origin), so trees with different origins compare correctly.
// Every vertex and points at most `sample_step` apart on every edge are sampled; distances to
// the other skeleton are exact point-to-segment distances.
HausdorffResult skeleton_hausdorff(const TreeGraph& original, const TreeGraph& other, const HausdorffOptions& options = {});

struct VertexErrorCheck {
    double max_error = 0.0;  // largest distance between a decoded vertex and its source vertex
    double bound = 0.0;      // √3·d/2
    bool within_bound = true;
};

// Compares decoded vertex k with original vertex decoded_to_source[k] (EncodedTree). A tolerance
// of 1e-5·(1 + |p|) covers float rounding of the stored positions.
VertexErrorCheck check_vertex_error(const TreeGraph& original, const TreeGraph& decoded, const std::vector<int>& decoded_to_source,
                                    double voxel_size);

}  // namespace treelobes::encode
