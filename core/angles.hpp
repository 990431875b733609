// Degrees and radians: species profiles, scanners and turtles state angles in degrees, and
// shape features report them so.
#pragma once

#include <numbers>

namespace treelobes {

inline constexpr double kRadiansPerDegree = std::numbers::pi / 180.0;
inline constexpr double kDegreesPerRadian = 180.0 / std::numbers::pi;

}  // namespace treelobes
