// The crown of one tree as an airborne survey delivers it: a clip of a field-mapped crown polygon
// holds ground returns, understorey under the crown, noise and, now and then, a return from a
// bird or a cloud far above the canopy. Features describe the crown, so these go first:
//   - noise: ASPRS classes 7 (low noise) and 18 (high noise);
//   - ground: class 2 returns; their lowest height is the ground level (z = 0 of the features),
//     so heights are heights above the lowest ground return, as a DTM would give on flat ground;
//   - high outliers: from the top down, points separated from the next lower point by a vertical
//     gap of more than `outlier_gap_m` (the crown itself has no such gap at its top);
//   - understorey (only when the ground level is known): from the top down, the first vertical gap
//     of more than max(understorey_gap_m, understorey_gap_fraction x top height) below which lies
//     nothing above half the top height; the points below that gap are other, lower plants.
// Clouds without classification lose only their high outliers. A crown is never emptied: when
// nothing would be left, the vegetation points are kept as they are.
#pragma once

#include "core/point_cloud.hpp"

#include <cstddef>
#include <optional>

namespace treelobes::classify {

struct CrownOptions {
    double outlier_gap_m = 5.0;
    double understorey_gap_m = 1.5;
    double understorey_gap_fraction = 0.1;
};

// What was removed from a clip (points), for the reports.
struct CrownCounts {
    std::size_t input = 0, noise = 0, ground = 0, high_outliers = 0, understorey = 0;
    bool ground_found = false;
    bool shape_features = true;  // false: too few crown points for the shape groups (set by compute_features)
};

struct CrownExtraction {
    PointCloud crown;               // the crown points with all their attributes
    std::optional<float> ground_z;  // lowest ground return (local z), when the clip has class-2 points
    CrownCounts counts;
};

CrownExtraction extract_crown(const PointCloud& cloud, const CrownOptions& options = {});

}  // namespace treelobes::classify
