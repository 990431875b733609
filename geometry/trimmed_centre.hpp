// The horizontal centre of a cloud without its outlying parts: the mean x, y of the points,
// recomputed a few times from only the share of points nearest to the last centre. A crown's
// stem stands under the bulk of its points; a branch reaching into a gap or a neighbour's limb
// that a segmentation left with it pulls the plain mean away from the stem.
#pragma once

#include <Eigen/Core>

#include <span>

namespace treelobes {

struct TrimmedCentreOptions {
    double keep = 0.8;  // share of the points, nearest to the centre, each round averages
    int rounds = 3;
};

// Throws Error(Internal) for no points, Error(Usage) for `keep` outside (0, 1] or rounds < 0.
// With keep = 1 or rounds = 0 it is the plain mean x, y.
Eigen::Vector2d trimmed_centre_xy(std::span<const Eigen::Vector3f> points, const TrimmedCentreOptions& options = {});

}  // namespace treelobes
