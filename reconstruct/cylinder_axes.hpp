// Skeleton nodes moved onto the axes of least-squares cylinders fitted to a stretch of branch.
//
// Why: sparse or one-sided scans see only the scanner-facing arc of a branch (WoodSKE SW:
// crown points lie on the lower, outer side of every branch), so nodes placed at centroids of
// bin clusters, or re-centred on their internode's points, sit ~0.6 r off the axis on the
// scanner side. A circle through one internode's few points cannot tell which side the axis is
// on, but a cylinder fitted to all points of a longer stretch of the branch (`window` metres of
// its axis, several internodes) is well conditioned even on a half ring: the
// bark's curvature across the stretch is measured from many rings at once (TreeQSM fits
// cylinders the same way, and is the reference of archi tree1).
//
// A fit is trusted only when it is plausible as a branch: enough points, a radius within limits,
// a small RMS residual relative to the radius, a cross-section as wide as the cylinder (a twig
// bent within the stretch, or a strip of bark, fits a cylinder much wider than the spread of
// its points; this also rejects arcs narrower than ~160 degrees, whose fits on the WoodSKE scans
// were right less often than not), bark seen over a wide enough arc, and an axis close to the
// skeleton's direction. Fits are made on windows centred a quarter window apart along each
// branch; every node takes the nearest window's trusted fit and moves across onto its axis
// (never along it) unless that is more than `max_shift` radii away. Nodes that the skeleton
// placed by circle fits on thick stems (`fixed`) stay.
//
// Off by default: on the WoodSKE scans it lowers the medians (HS 0.0188 -> 0.0175, OR 0.0079 ->
// 0.0075, SW 0.0280 -> 0.0271), but on archi tree1 it moves crown nodes 2-3 cm away from the
// TreeQSM axes (median 0.0309 -> 0.0333), and leafy synthetic recall drops 0.929 -> 0.921.
#pragma once

#include "core/tree_graph.hpp"
#include "geometry/cylinder_fit.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <span>
#include <vector>

namespace treelobes {

struct CylinderAxesOptions {
    bool enabled = false;       // off by default: it lowers the WoodSKE medians but raises archi tree1's (see docs/reconstruct.md)
    float window = 0.4f;        // metres of branch axis whose points one cylinder is fitted to
    int min_points = 20;        // stretches with fewer points keep their nodes
    float min_radius = 0.004f;  // metres: thinner fits are rejected (noise fits)
    float max_radius = 0.15f;   // metres: wider fits are rejected
    float max_rms = 0.25f;      // x radius: RMS of the points' distances from the cylinder surface
    float min_spread = 0.7f;    // x radius: the points' cross-section spread (RMS about each internode's centroid) must reach this
    float min_arc = 100.0f;     // degrees of bark around the fitted axis that must hold points
    float max_tilt = 30.0f;     // degrees between the fitted axis and the skeleton's direction
    float max_shift = 1.5f;     // x radius: nodes that would move farther stay where they are
};

// Moves the non-fixed nodes of `tree` across onto trusted cylinder fits (see above); a window
// of a dense scan is thinned evenly to at most 80 points before fitting.
// `point_internode[i]` is the node at the upper end of point i's internode (< 1: ignored). The
// stretch around a node follows its branch (main children first) and never crosses into a
// lateral. All fits are made on the input positions, then applied together. Nodes u with
// `fixed[u]` stay (empty `fixed`: none). Returns the number of nodes moved. Throws Error(Usage)
// for options out of range.
std::size_t fit_cylinder_axes(TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                              const CylinderAxesOptions& options, const std::vector<bool>& fixed = {});

}  // namespace treelobes
