// Local-geometry features: normals, curvature and eigen-features from the covariance of each
// voxel point's k nearest neighbours (PCL's normal estimation: pcl::eigen33 on the
// neighbourhood covariance; normal = eigenvector of the smallest eigenvalue, curvature =
// lambda_min / sum lambda as in pcl::solvePlaneParameters). Neighbours come from the frame's kNN
// table (one query shared with the cleaning and the skeleton, see TreeFrame).
#include "classify/feature_groups.hpp"
#include "core/angles.hpp"
#include "core/parallel.hpp"
#include "geometry/kd_tree.hpp"

#include <pcl/common/eigen.h>

#include <algorithm>
#include <cmath>

namespace treelobes::classify::detail {

namespace {

constexpr int kAngleBins = 9;       // 10 degree bins over 0..90
constexpr int kLayerAngleBins = 6;  // 15 degree bins per crown third
constexpr int kCurvatureBins = 8;   // over 0 .. 1/3 (the maximum of lambda_min / sum)
constexpr int kDirectionBins = 6;   // 15 degree bins of linear directions

struct LocalShape {
    Eigen::Vector3f normal{0, 0, 1};
    Eigen::Vector3f direction{0, 0, 1};  // eigenvector of the largest eigenvalue
    float l1 = 0, l2 = 0, l3 = 0;        // eigenvalues / their sum, l1 >= l2 >= l3
    bool valid = false;
};

// `knn`: the frame's table over `points`, at least k wide; its first k columns are the k nearest.
std::vector<LocalShape> local_shapes(const std::vector<Eigen::Vector3f>& points, const KnnTable& knn, int k,
                                     std::vector<float>& nn_distance) {
    std::vector<LocalShape> shapes(points.size());
    nn_distance.assign(points.size(), 0.0f);
    treelobes::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
        const int* row = knn.row(i);
        Eigen::Vector3d mean = points[i].cast<double>();
        int n = 1;
        for (int j = 0; j < k; ++j)
            if (row[j] >= 0) mean += points[row[j]].cast<double>(), ++n;
        nn_distance[i] = std::sqrt(knn.row_distances(i)[0]);
        if (n < 4) return;
        mean /= n;
        Eigen::Matrix3d cov = (points[i].cast<double>() - mean) * (points[i].cast<double>() - mean).transpose();
        for (int j = 0; j < k; ++j)
            if (row[j] >= 0) {
                const Eigen::Vector3d d = points[row[j]].cast<double>() - mean;
                cov += d * d.transpose();
            }
        cov /= n;
        Eigen::Matrix3d vectors;
        Eigen::Vector3d values;  // ascending
        pcl::eigen33(cov, vectors, values);
        const double sum = values.sum();
        if (!(sum > 0)) return;
        LocalShape& s = shapes[i];
        s.normal = vectors.col(0).cast<float>().normalized();
        s.direction = vectors.col(2).cast<float>().normalized();
        s.l1 = static_cast<float>(values(2) / sum);
        s.l2 = static_cast<float>(values(1) / sum);
        s.l3 = static_cast<float>(std::max(0.0, values(0)) / sum);
        s.valid = true;
    });
    return shapes;
}

int bin(double value, double width, int bins) { return std::clamp(static_cast<int>(value / width), 0, bins - 1); }

}  // namespace

void describe_normals(Catalogue& c) {
    for (int k = 0; k < kAngleBins; ++k)
        c.add(indexed("normal_elevation", k), "1",
              "fraction of points whose normal line rises " + std::to_string(k * 10) + "-" + std::to_string(k * 10 + 10) +
                      " deg above the horizontal plane (asin |n_z|); normals from PCA of the k nearest voxel points");
    for (int k = 0; k < kAngleBins; ++k)
        c.add(indexed("normal_axis_angle", k), "1",
              "fraction of points (r > 1 voxel) whose normal line makes " + std::to_string(k * 10) + "-" + std::to_string(k * 10 + 10) +
                      " deg with the horizontal direction away from the tree axis (acos |n . u_r|)");
    const char* thirds[] = {"lower", "middle", "upper"};
    for (int t = 0; t < 3; ++t)
        for (int k = 0; k < kLayerAngleBins; ++k)
            c.add(std::string("normal_elevation_") + thirds[t] + "_" + std::to_string(k), "1",
                  std::string("as normal_elevation, 15 deg bins (") + std::to_string(k * 15) + "-" + std::to_string(k * 15 + 15) +
                          " deg), points of the " + thirds[t] + " third of the height");
    c.add("normal_vertical_mean", "1", "mean |n_z|");
    c.add("normal_vertical_sd", "1", "standard deviation of |n_z|");
    c.add("normal_axis_mean", "1", "mean |n . u_r| (1 = surfaces facing away from the axis)");
    for (int k = 0; k < kCurvatureBins; ++k)
        c.add(indexed("curvature", k), "1",
              "fraction of points with surface variation lambda_min / sum lambda in bin " + std::to_string(k) + " of 8 over [0, 1/3]");
    c.add("curvature_mean", "1", "mean surface variation");
    c.add("curvature_median", "1", "median surface variation");
    c.add("linearity_mean", "1", "mean (l1 - l2) / l1 (eigenvalues l1 >= l2 >= l3 of the neighbourhood covariance)");
    c.add("planarity_mean", "1", "mean (l2 - l3) / l1");
    c.add("scattering_mean", "1", "mean l3 / l1");
    c.add("linear_fraction", "1", "fraction of points whose largest of linearity, planarity, scattering is linearity (twigs, stems)");
    c.add("planar_fraction", "1", "fraction dominated by planarity (leaves, bark)");
    c.add("scatter_fraction", "1", "fraction dominated by scattering (foliage volume)");
    for (int k = 0; k < kDirectionBins; ++k)
        c.add(indexed("linear_direction", k), "1",
              "among linear points: fraction whose principal direction rises " + std::to_string(k * 15) + "-" +
                      std::to_string(k * 15 + 15) + " deg above the horizontal (branch directions)");
    c.add("omnivariance_mean", "1", "mean cube root of l1 l2 l3 (eigenvalues normalised to sum 1)");
    c.add("anisotropy_mean", "1", "mean (l1 - l3) / l1");
    c.add("eigenentropy_mean", "1", "mean -sum l ln l");
    c.add("nn_distance_ratio", "1", "mean nearest-neighbour distance of the voxel points / voxel size (sparseness)");
}

void compute_normals(const TreeFrame& f, FeatureSink& out) {
    std::vector<float> nn_distance;
    const auto shapes = local_shapes(f.points, *f.neighbours, std::min(f.options->normal_neighbours, f.neighbours->k), nn_distance);
    std::vector<double> elevation(kAngleBins, 0), axis_angle(kAngleBins, 0), curvature(kCurvatureBins, 0), direction(kDirectionBins, 0);
    std::vector<std::vector<double>> layered(3, std::vector<double>(kLayerAngleBins, 0));
    std::vector<double> layer_count(3, 0);
    std::vector<float> vertical, surface_variation;
    double n = 0, n_axis = 0, axis_sum = 0, lin = 0, pla = 0, sca = 0, omni = 0, aniso = 0, entropy = 0;
    double n_linear = 0, n_planar = 0, n_scatter = 0;
    for (std::size_t i = 0; i < shapes.size(); ++i) {
        const LocalShape& s = shapes[i];
        if (!s.valid) continue;
        n += 1;
        const double nz = std::min(1.0f, std::abs(s.normal.z()));
        const double elev = std::asin(nz) * kDegreesPerRadian;
        elevation[bin(elev, 10, kAngleBins)] += 1;
        const int third = std::min(2, static_cast<int>(f.rel_height[i] * 3));
        layered[third][bin(elev, 15, kLayerAngleBins)] += 1;
        layer_count[third] += 1;
        vertical.push_back(static_cast<float>(nz));
        if (f.radius[i] > f.voxel) {
            const Eigen::Vector2f radial = f.points[i].head<2>() / f.radius[i];
            const double c = std::min(1.0f, std::abs(s.normal.head<2>().dot(radial)));
            axis_angle[bin(std::acos(c) * kDegreesPerRadian, 10, kAngleBins)] += 1;
            axis_sum += c, n_axis += 1;
        }
        surface_variation.push_back(s.l3);
        curvature[bin(s.l3, 1.0 / 3.0 / kCurvatureBins, kCurvatureBins)] += 1;
        const double linearity = (s.l1 - s.l2) / s.l1, planarity = (s.l2 - s.l3) / s.l1, scattering = s.l3 / s.l1;
        lin += linearity, pla += planarity, sca += scattering;
        if (linearity >= planarity && linearity >= scattering) {
            n_linear += 1;
            direction[bin(std::asin(std::min(1.0f, std::abs(s.direction.z()))) * kDegreesPerRadian, 15, kDirectionBins)] += 1;
        } else if (planarity >= scattering) {
            n_planar += 1;
        } else {
            n_scatter += 1;
        }
        omni += std::cbrt(double(s.l1) * s.l2 * s.l3);
        aniso += (s.l1 - s.l3) / s.l1;
        for (float l : {s.l1, s.l2, s.l3})
            if (l > 0) entropy -= l * std::log(l);
    }
    auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };
    for (int k = 0; k < kAngleBins; ++k) out.add(indexed("normal_elevation", k), ratio(elevation[k], n));
    for (int k = 0; k < kAngleBins; ++k) out.add(indexed("normal_axis_angle", k), ratio(axis_angle[k], n_axis));
    const char* thirds[] = {"lower", "middle", "upper"};
    for (int t = 0; t < 3; ++t)
        for (int k = 0; k < kLayerAngleBins; ++k)
            out.add(std::string("normal_elevation_") + thirds[t] + "_" + std::to_string(k), ratio(layered[t][k], layer_count[t]));
    const Moments mv = moments(vertical);
    out.add("normal_vertical_mean", mv.mean);
    out.add("normal_vertical_sd", mv.sd);
    out.add("normal_axis_mean", ratio(axis_sum, n_axis));
    for (int k = 0; k < kCurvatureBins; ++k) out.add(indexed("curvature", k), ratio(curvature[k], n));
    out.add("curvature_mean", moments(surface_variation).mean);
    out.add("curvature_median", quantile(surface_variation, 0.5));
    out.add("linearity_mean", ratio(lin, n));
    out.add("planarity_mean", ratio(pla, n));
    out.add("scattering_mean", ratio(sca, n));
    out.add("linear_fraction", ratio(n_linear, n));
    out.add("planar_fraction", ratio(n_planar, n));
    out.add("scatter_fraction", ratio(n_scatter, n));
    for (int k = 0; k < kDirectionBins; ++k) out.add(indexed("linear_direction", k), ratio(direction[k], n_linear));
    out.add("omnivariance_mean", ratio(omni, n));
    out.add("anisotropy_mean", ratio(aniso, n));
    out.add("eigenentropy_mean", ratio(entropy, n));
    out.add("nn_distance_ratio", moments(nn_distance).mean / f.voxel);
}

}  // namespace treelobes::classify::detail
