// Scan group: what the scanner, not the tree, decides. Its one feature, the point density over
// the crown's ground plan, is deliberately NOT density-invariant: it tells airborne scans (tens to
// a few hundred points per m^2) from terrestrial ones (thousands), so that a routed JointBoost
// model (classify/jointboost.hpp) can send each tree to the sub-model of its scan kind. JointBoost
// never splits on it (is_scan_descriptor()); the XGBoost baseline gets the same table and may.
#include "classify/feature_groups.hpp"

#include <algorithm>
#include <numbers>

namespace treelobes::classify {

bool is_scan_descriptor(const std::string& feature_name) { return feature_name == kScanDensityFeature; }

namespace detail {

void describe_scan(Catalogue& c) {
    c.add(kScanDensityFeature, "1/m^2",
          "input points (before cleaning and voxels) per m^2 of the crown disc pi R^2. Scanner-dependent on purpose (halves "
          "when the scan is thinned to 50 %): routes a tree to the sub-model of its scan kind, never a JointBoost stump feature");
}

// The disc, not the occupied ground-plan cells: a small airborne crown occupies few cells of its
// sparse voxel points, which overstated its density up to terrestrial values (1,190 points/m^2
// for a 3 m lagerstroemia against 36-205 for other airborne trees; per disc: 36-158 against 850
// and more for every terrestrial tree of the 480-tree set).
void compute_scan(std::size_t input_points, float crown_radius, FeatureSink& out) {
    // A crown of one point or one column has no width: a disc of 0.5 m keeps the density finite.
    const double r = std::max(crown_radius, 0.5f);
    out.add(kScanDensityFeature, static_cast<double>(input_points) / (std::numbers::pi * r * r));
}

}  // namespace detail
}  // namespace treelobes::classify
