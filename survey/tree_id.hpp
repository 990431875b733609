// A tree's id across a survey, stable under re-runs, shards and other tilings: it is derived
// from the tree's stem base only (docs/survey.md).
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace treelobes::survey {

// The 1 cm cell of the stem base's x, y in the CRS (metres), named by its lower-left corner:
// "<x>_<y>" with two decimals, e.g. "500012.34_5400056.78". The coordinates are first rounded to
// 0.1 mm, so that the float noise of another local frame (another tile origin) does not move a
// base that sits on a cell edge (LAS coordinates on a 1 mm or 1 cm grid) across it; the cell is
// then taken exactly in integers.
std::string stable_tree_id(double x, double y);

}  // namespace treelobes::survey

namespace treelobes::survey {

// stable_tree_id of every base (original coordinates, x and y used). Two bases in one 1 cm cell
// (which real stems cannot share; a segmentation error or a geographic CRS can) keep the id for
// the lower base and get "~2", "~3", ... in the order of their base z, then of their position in
// `bases`.
std::vector<std::string> stable_tree_ids(const std::vector<Eigen::Vector3d>& bases);

}  // namespace treelobes::survey
