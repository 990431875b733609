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

}  // namespace treelobes
