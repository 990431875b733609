// Joining points read from several files (retiling, a tile's buffer): the files must carry the
// same attributes, and positions move from each piece's origin to the joined cloud's.
#pragma once

#include "core/point_cloud.hpp"

#include <string>

namespace treelobes::survey {

// The attributes a cloud carries, as a comparable text ("intensity;...;treeID:int32;").
std::string attribute_signature(const PointCloud& cloud);

// Appends the points of `piece` (with every attribute) to `into`; the caller checked that their
// attribute signatures agree.
void append_points(PointCloud& into, const PointCloud& piece);

}  // namespace treelobes::survey
