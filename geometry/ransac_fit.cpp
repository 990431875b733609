#include "geometry/ransac_fit.hpp"

#include <Eigen/QR>
#include <pcl/console/print.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/ransac.h>
#include <pcl/sample_consensus/sac_model_circle.h>
#include <pcl/sample_consensus/sac_model_perpendicular_plane.h>
#include <pcl/sample_consensus/sac_model_plane.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace treelobes {

namespace {

// Degenerate samples ("points too similar or collinear") are routine when RANSAC runs on thin
// stem slices; a failed fit is handled by the caller, so PCL's console messages are only noise
// on stderr. Silenced once, before the first fit.
void silence_pcl_console() {
    static const bool silenced = [] {
        pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
        return true;
    }();
    (void)silenced;
}

pcl::PointCloud<pcl::PointXYZ>::Ptr to_pcl(std::span<const Eigen::Vector3f> points) {
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    cloud->reserve(points.size());
    for (const auto& p : points) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    return cloud;
}

// Gauss-Newton on sum (|p - c| - r)^2, started from the RANSAC circle.
void refine_circle(std::span<const Eigen::Vector2f> points, const std::vector<int>& inliers, Eigen::Vector2f& c, float& r) {
    for (int iteration = 0; iteration < 10; ++iteration) {
        Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        for (int i : inliers) {
            const Eigen::Vector2d d = (points[i] - c).cast<double>();
            const double dist = d.norm();
            if (dist < 1e-9) continue;
            const Eigen::Vector3d jacobian(-d.x() / dist, -d.y() / dist, -1.0);
            const double residual = dist - r;
            normal += jacobian * jacobian.transpose();
            rhs -= jacobian * residual;
        }
        const Eigen::Vector3d step = normal.ldlt().solve(rhs);
        if (!step.allFinite()) return;
        c += step.head<2>().cast<float>();
        r += static_cast<float>(step.z());
        if (step.norm() < 1e-7) return;
    }
}

}  // namespace

PlaneFit fit_plane(std::span<const Eigen::Vector3f> points, float threshold, int max_iterations, float max_tilt_degrees) {
    PlaneFit fit;
    if (points.size() < 3) return fit;
    silence_pcl_console();
    pcl::SampleConsensusModelPlane<pcl::PointXYZ>::Ptr model;
    if (max_tilt_degrees > 0) {
        auto tilted = std::make_shared<pcl::SampleConsensusModelPerpendicularPlane<pcl::PointXYZ>>(to_pcl(points));
        tilted->setAxis(Eigen::Vector3f::UnitZ());
        tilted->setEpsAngle(max_tilt_degrees * std::numbers::pi_v<float> / 180.0f);
        model = tilted;
    } else {
        model = std::make_shared<pcl::SampleConsensusModelPlane<pcl::PointXYZ>>(to_pcl(points));
    }
    pcl::RandomSampleConsensus<pcl::PointXYZ> ransac(model, threshold);
    ransac.setMaxIterations(max_iterations);
    if (!ransac.computeModel()) return fit;
    Eigen::VectorXf coefficients;
    ransac.getModelCoefficients(coefficients);
    pcl::Indices inliers;
    ransac.getInliers(inliers);
    if (coefficients.size() != 4 || inliers.empty()) return fit;
    Eigen::Vector3f normal = coefficients.head<3>();
    float offset = coefficients[3];
    const float norm = normal.norm();
    if (!(norm > 0)) return fit;
    normal /= norm;
    offset /= norm;
    if (normal.z() < 0) {
        normal = -normal;
        offset = -offset;
    }
    fit.ok = true;
    fit.normal = normal;
    fit.offset = offset;
    fit.inliers.assign(inliers.begin(), inliers.end());
    return fit;
}

CircleFit fit_circle(std::span<const Eigen::Vector2f> points, float threshold, float min_radius, float max_radius, int max_iterations) {
    CircleFit fit;
    if (points.size() < 5) return fit;
    silence_pcl_console();
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    for (const auto& p : points) cloud->push_back(pcl::PointXYZ(p.x(), p.y(), 0.0f));
    auto model = std::make_shared<pcl::SampleConsensusModelCircle2D<pcl::PointXYZ>>(cloud);
    model->setRadiusLimits(min_radius, max_radius);
    pcl::RandomSampleConsensus<pcl::PointXYZ> ransac(model, threshold);
    ransac.setMaxIterations(max_iterations);
    if (!ransac.computeModel()) return fit;
    Eigen::VectorXf coefficients;
    ransac.getModelCoefficients(coefficients);
    pcl::Indices found;
    ransac.getInliers(found);
    if (coefficients.size() != 3 || found.size() < 5) return fit;
    std::vector<int> inliers(found.begin(), found.end());
    Eigen::Vector2f centre(coefficients[0], coefficients[1]);
    float radius = coefficients[2];
    refine_circle(points, inliers, centre, radius);
    if (!(radius >= min_radius && radius <= max_radius) || !centre.allFinite()) return fit;

    double sum = 0;
    std::array<bool, 36> sector{};
    std::size_t count = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector2f d = points[i] - centre;
        const float residual = std::abs(d.norm() - radius);
        if (residual > threshold) continue;
        sum += static_cast<double>(residual) * residual;
        ++count;
        const double angle = std::atan2(d.y(), d.x()) + std::numbers::pi;
        sector[std::min<std::size_t>(35, static_cast<std::size_t>(angle / (2 * std::numbers::pi) * 36))] = true;
    }
    if (count < 5) return fit;
    fit.ok = true;
    fit.centre = centre;
    fit.radius = radius;
    fit.inliers = count;
    fit.rms = static_cast<float>(std::sqrt(sum / static_cast<double>(count)));
    fit.coverage = static_cast<float>(std::count(sector.begin(), sector.end(), true)) / 36.0f;
    return fit;
}

std::optional<Circle2d> fit_circle_least_squares(std::span<const Eigen::Vector2d> points) {
    if (points.size() < 3) return std::nullopt;
    const auto n = static_cast<Eigen::Index>(points.size());
    Eigen::MatrixXd a(n, 3);
    Eigen::VectorXd b(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Vector2d& p = points[static_cast<std::size_t>(i)];
        a.row(i) << p.x(), p.y(), 1.0;
        b(i) = -p.squaredNorm();
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
    if (qr.rank() < 3) return std::nullopt;  // coincident or collinear points: any circle would be a guess
    const Eigen::Vector3d s = qr.solve(b);
    Circle2d circle;
    circle.centre = Eigen::Vector2d(-0.5 * s(0), -0.5 * s(1));
    const double r2 = circle.centre.squaredNorm() - s(2);
    if (!(r2 > 0) || !circle.centre.allFinite()) return std::nullopt;
    circle.radius = std::sqrt(r2);
    return circle;
}

std::optional<Eigen::Vector3d> fit_height_plane_least_squares(std::span<const Eigen::Vector3d> points) {
    if (points.size() < 3) return std::nullopt;
    const auto n = static_cast<Eigen::Index>(points.size());
    Eigen::MatrixXd a(n, 3);
    Eigen::VectorXd b(n);
    for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Vector3d& p = points[static_cast<std::size_t>(i)];
        a.row(i) << 1.0, p.x(), p.y();
        b(i) = p.z();
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
    if (qr.rank() < 3) return std::nullopt;  // the points lie on a line: any plane through it would be a guess
    const Eigen::Vector3d plane = qr.solve(b);
    if (!plane.allFinite()) return std::nullopt;
    return plane;
}

}  // namespace treelobes
