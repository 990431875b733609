// The part of a true skeleton that a simulated scan can show. A synthetic tree's skeleton holds
// every twig, also those hidden in foliage or too thin for the scan's raster to hit; scoring a
// reconstruction against all of it measures the scan, not the reconstruction. Synthetic scans
// label each point with the reference internode it lies on (`internode`: the vertex whose
// internode parent -> vertex it hit, docs/species.md), so the visible part is known exactly.
#pragma once

#include "reconstruct/skeleton_eval.hpp"

#include <cstddef>
#include <span>

namespace treelobes {

// The vertices of `reference` whose internode holds at least `min_points` of the scan's points
// (`point_internode`: one reference vertex index per point, negative = none), with every vertex
// on their way to the root, as a skeleton of the same kind. Throws Error(Usage) when the
// reference is not one tree rooted at vertex 0, and Error(InvalidInput) when no internode is seen.
SkeletonGraph visible_reference(const SkeletonGraph& reference, std::span<const double> point_internode, std::size_t min_points);

// A skeleton scored against the part of `reference` its scan shows, each side against its own
// part. What the skeleton holds (skeleton -> reference distances, branch precision) against every
// internode the scan touched (one point or more): a branch built from the three returns of a thin
// twig lies on wood, and is right. What it should hold (reference -> skeleton distances, recall,
// length, trunk) against the internodes holding `min_points`: a twig of one return cannot be
// followed, and is not missed. With one reference for both, a leaf-off scan whose sparse twigs
// were kept scored precision 0.25 (12 of 49) although every branch lay within 0.16 m of wood it
// hit. Throws as visible_reference does.
SkeletonComparison compare_with_visible_part(const SkeletonGraph& skeleton, const SkeletonGraph& reference,
                                             std::span<const double> point_internode, std::size_t min_points,
                                             const EvalOptions& options = {});

}  // namespace treelobes
