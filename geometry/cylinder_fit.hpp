// Least-squares cylinders through points: the axis and radius of a stretch of branch seen on a
// partial ring (a one-sided scan). Used by the skeleton's cylinder-axis refinement and by stem
// fits of whole plots.
#pragma once

#include <Eigen/Core>

#include <span>

namespace treelobes {

struct CylinderFit {
    bool converged = false;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();       // on the axis, level with the points' centroid
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // unit
    double radius = 0;
    double rms = 0;  // RMS of |distance to the axis - radius| (metres)
    double arc = 0;  // degrees around the axis covered by points (360 minus the widest empty gap)
};

// Least-squares cylinder (Levenberg-Marquardt over axis position, direction and radius) through
// `points`, started from the axis through `point` along `direction` with radius `radius`. Points
// farther than 3 RMS from the first fit's surface are dropped and the fit repeated once.
// converged = false with fewer than 6 points or when the iteration fails.
CylinderFit fit_cylinder(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& point, const Eigen::Vector3d& direction,
                         double radius);

}  // namespace treelobes
