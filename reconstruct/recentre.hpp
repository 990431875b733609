// Lateral re-centring of skeleton internodes on the points assigned to them.
//
// Why: on leafy TLS scans the skeleton of thin branches runs beside the bark rather than along
// it (per-branch dumps of bench/reconstruct_synthetic_recall.sh: missed willow, palm and
// mahogany branches lie 5-15 cm from the true axis while the points assigned to those very
// internodes are nearly all wood and centred within 2-4 cm of it). Bin clusters of a crown mix
// bark with leaf clutter and neighbouring twigs, and the chains drawn through them are smoothed
// and resampled, so a node ends up where no points of its own internode are. Each internode's
// points tell where its segment should pass: their centre, taken across the segment only (the
// component along it would just slide the node along the branch), reweighted towards the dense
// ring of bark so that leaves sharing the internode pull less.
//
// Only nodes lying outside their branch move (farther from the points' centroid than
// inside_band x their spread: on one-sided scans the centroid of the visible arc is no better
// an axis than the skeleton's own, and moving every node made the WoodSKE medians worse), and only
// on thin internodes: the points of a thick stem lie on a (often one-sided) ring whose centroid
// sits off the axis, where the skeleton's circle fits already put the node; an internode counts
// as thin when the RMS distance of its points from their centroid (across the segment) is below
// `max_spread`.
#pragma once

#include "core/tree_graph.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <span>
#include <vector>

namespace treelobes {

struct RecentreOptions {
    bool enabled = true;       // off: the skeleton is left as extracted
    float max_spread = 0.10f;  // metres: internodes whose points spread wider around their centroid stay put
    int min_points = 3;        // internodes with fewer points stay put
    int passes = 3;            // Gaussian reweighting rounds around the centre (0 = plain centroid)
    double min_sigma = 0.02;   // metres: the reweighting never narrows below this
    double inside_band = 1.0;  // x the points' spread: nodes closer than this to their centroid are inside
                               // their branch and stay (0 = every thin node moves)
    double dead_band = 0.5;    // x the bark's spread around the robust centre: a moving node stops at this
                               // distance from it (0 = right onto the centre)
};

// Moves every non-root node u towards the lateral centre of u's internode points (their
// offsets across the segment parent(u) -> u, averaged with weights that favour the densest
// part, see recentre.cpp) when it lies outside its branch, up to dead_band x the bark's spread
// from that centre; all measured on the input positions. `point_internode[i]` is the node at the
// upper end of point i's internode (< 1: the point is ignored). Nodes u with `fixed[u]` stay put
// (an empty `fixed`: none): the skeleton placed them on an axis measured by circle fits, which
// the points of their internode (often a patch of one side's bark) would only pull off. Returns
// the number of nodes moved. Throws Error(Usage) for options out of range.
std::size_t recentre_internodes(TreeGraph& tree, std::span<const Eigen::Vector3f> points, std::span<const int> point_internode,
                                const RecentreOptions& options, const std::vector<bool>& fixed = {});

}  // namespace treelobes
