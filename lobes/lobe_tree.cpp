#include "lobes/lobe_tree.hpp"

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "geometry/grid_thinning.hpp"
#include "geometry/kd_tree.hpp"
#include "lobes/lobe_split.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

namespace treelobes::lobes {

namespace {

class StageClock {
public:
    explicit StageClock(std::vector<std::pair<std::string, double>>& out) : out_(out) {}
    void mark(const std::string& stage) {
        const auto now = std::chrono::steady_clock::now();
        out_.emplace_back(stage, std::chrono::duration<double>(now - last_).count());
        last_ = now;
    }

private:
    std::vector<std::pair<std::string, double>>& out_;
    std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

Eigen::Vector3f seed_direction(const TreeGraph& tree, const LobeCluster& cluster, std::span<const Eigen::Vector3f> points) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int i : cluster.points) centroid += points[i].cast<double>();
    centroid /= static_cast<double>(cluster.points.size());
    const Eigen::Vector3f from = tree.nodes[cluster.seed_node].position;
    Eigen::Vector3f d = centroid.cast<float>() - from;
    if (d.norm() < 1e-6f) d = tree.nodes[cluster.first_node].position - from;  // centroid on p_i: the edge's direction
    if (d.norm() < 1e-6f) d = Eigen::Vector3f::UnitZ();
    return d.normalized();
}

// At most `max_points` of the cluster: the first point (in input order) of each cell of a grid
// just coarse enough. Alpha shapes of dense clusters cost seconds; their hull does not need
// every point.
std::vector<Eigen::Vector3f> thinned(std::vector<Eigen::Vector3f> points, std::size_t max_points) {
    if (points.size() <= max_points) return points;
    Eigen::Vector3f lo = points[0], hi = points[0];
    for (const auto& p : points) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    const Eigen::Vector3f extent = (hi - lo).cwiseMax(Eigen::Vector3f::Constant(1e-3f));
    float cell = std::cbrt(extent.prod() / static_cast<float>(max_points));
    for (;;) {
        std::vector<Eigen::Vector3f> kept;
        for (const std::size_t i : first_point_per_cell(points, cell, lo)) kept.push_back(points[i]);
        if (kept.size() <= max_points) return kept;
        cell *= 1.25f;
    }
}

// Face budget of each lobe: its share of the total by surface area, within [min, max].
std::size_t lobe_face_budget(double area, double total_area, const LobeOptions& o) {
    const double share = total_area > 0 ? area / total_area : 1.0;
    const auto faces = static_cast<std::size_t>(std::llround(share * static_cast<double>(o.face_budget)));
    return std::clamp(faces, o.min_lobe_faces, o.max_lobe_faces);
}

// Points the reconstruction dropped as outliers (isolated leaves at the crown's rim, where a
// scan is sparse) still belong to the tree: each one closer than `reach` to a lobe's cluster
// point, not classified ground and not below that cluster's lowest point, is added to the
// nearest lobe's points for its occupancy, so that texturing covers it.
std::size_t attach_dropped_points(const PointCloud& cloud, const std::vector<int>& point_internode, std::vector<Lobe>& lobes, float reach) {
    if (!(reach > 0) || lobes.empty()) return 0;
    std::vector<Eigen::Vector3f> cluster_points;
    std::vector<std::size_t> owner;  // lobe of each indexed point
    std::vector<float> lowest(lobes.size(), std::numeric_limits<float>::max());
    for (std::size_t l = 0; l < lobes.size(); ++l)
        for (const auto& p : lobes[l].cluster_points) {
            cluster_points.push_back(p);
            owner.push_back(l);
            lowest[l] = std::min(lowest[l], p.z());
        }
    if (cluster_points.empty()) return 0;
    const KdTree index(cluster_points);
    std::vector<std::vector<Eigen::Vector3f>> added(lobes.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (point_internode[i] >= 0 || (!cloud.classification.empty() && cloud.classification[i] == 2)) continue;
        const Eigen::Vector3f& p = cloud.positions[i];
        float squared_distance = 0;
        const int nearest = index.nearest(p, &squared_distance);
        if (nearest < 0 || !(squared_distance < reach * reach)) continue;
        const std::size_t lobe = owner[static_cast<std::size_t>(nearest)];
        if (p.z() >= lowest[lobe]) added[lobe].push_back(p);
    }
    std::size_t count = 0;
    for (std::size_t l = 0; l < lobes.size(); ++l) {
        count += added[l].size();
        lobes[l].cluster_points.insert(lobes[l].cluster_points.end(), added[l].begin(), added[l].end());
    }
    return count;
}

// Share of the points labelled leaf (`attribute` is 0), -1 without labels.
float leaf_share(const PointCloud& cloud, const std::string& attribute, const std::vector<int>& points) {
    const ExtraAttribute* wood = attribute.empty() ? nullptr : cloud.extra(attribute);
    if (wood == nullptr || points.empty()) return -1.0f;
    const auto leaves = std::count_if(points.begin(), points.end(), [&](int i) { return wood->values[static_cast<std::size_t>(i)] == 0; });
    return static_cast<float>(leaves) / static_cast<float>(points.size());
}

// d' measured on the input's own wood labels (the bark samples of a CG model), per node; empty
// when the input has no labels.
std::vector<float> measured_lobe_diameter(const PointCloud& cloud, const TreeReconstruction& r, const ReconstructOptions& ro,
                                          const LobeOptions& o) {
    const ExtraAttribute* labels = o.leaf_label_attribute.empty() ? nullptr : cloud.extra(o.leaf_label_attribute);
    if (labels == nullptr) return {};
    std::vector<char> wood(cloud.size());
    for (std::size_t i = 0; i < wood.size(); ++i) wood[i] = labels->values[i] != 0 ? 1 : 0;
    return wood_lobe_diameter(r.skeleton, cloud.positions, r.point_internode, wood, r.diameters.lobe_diameter,
                              static_cast<float>(ro.allometry.fs), o.wood_measurement);
}

}  // namespace

LobeTree build_lobe_tree(const PointCloud& cloud, const TreeReconstruction& r, const ReconstructOptions& ro, const std::string& species,
                         const LobeOptions& o, LobeReport* report_out) {
    if (o.min_lobe_faces < 4 || o.max_lobe_faces < o.min_lobe_faces) throw Error::usage("lobes: face limits must satisfy 4 <= min <= max");
    check_wood_measurement(o.wood_measurement);
    if (r.point_internode.size() != cloud.size()) throw Error::usage("lobes: the reconstruction belongs to another cloud");
    LobeReport report;
    StageClock clock(report.seconds);
    const TreeGraph& tree = r.skeleton;
    const std::span<const Eigen::Vector3f> points(cloud.positions);

    const EdgeConfidence confidence =
            edge_confidence(tree, points, r.point_internode, r.diameters.lobe_diameter, measured_lobe_diameter(cloud, r, ro, o));
    MainSplit split = split_at_low_confidence(tree, confidence, r.point_internode);
    report.low_confidence_edges = confidence.low_count();
    report.wood_measured_edges = confidence.measured_raised;
    report.clusters = split.clusters.size();
    clock.mark("confidence");

    // Alpha shapes of the clusters, in parallel; results by index keep the output deterministic.
    std::vector<AlphaShapeResult> shapes(split.clusters.size());
    treelobes::parallel_for(std::size_t{0}, split.clusters.size(), [&](std::size_t c) {
        const LobeCluster& cluster = split.clusters[c];
        if (cluster.points.size() < o.min_cluster_points) return;
        std::vector<Eigen::Vector3f> cluster_points;
        cluster_points.reserve(cluster.points.size());
        for (int i : cluster.points) cluster_points.push_back(points[i]);
        shapes[c] = alpha_shape(thinned(std::move(cluster_points), o.max_shape_points), o.alpha);
    });
    clock.mark("alpha shapes");

    std::vector<std::size_t> kept;  // clusters that become lobes
    double total_area = 0;
    for (std::size_t c = 0; c < split.clusters.size(); ++c) {
        const LobeCluster& cluster = split.clusters[c];
        if (!shapes[c].mesh.faces.empty()) {
            kept.push_back(c);
            total_area += shapes[c].mesh.area();
            report.faces_before_simplification += shapes[c].mesh.faces.size();
            continue;
        }
        // No lobe: the cluster's edges go back to the main structure (documented in docs/lobes.md).
        ++(cluster.points.size() < o.min_cluster_points ? report.kept_small : report.kept_no_shape);
        for (int u : cluster.nodes) split.main[u] = 1;
    }

    LobeTree out;
    out.species = species;
    out.beta = ro.skeleton.beta;
    out.gamma = ro.allometry.gamma;
    out.fs = ro.allometry.fs;
    out.alpha_factor = o.alpha.alpha_factor;
    out.root_diameter = r.summary.root_diameter;
    std::vector<int> new_index;
    out.skeleton = keep_nodes(tree, std::vector<bool>(split.main.begin(), split.main.end()), new_index);
    out.skeleton.origin = tree.origin;

    out.lobes.resize(kept.size());
    treelobes::parallel_for(std::size_t{0}, kept.size(), [&](std::size_t k) {
        const LobeCluster& cluster = split.clusters[kept[k]];
        Lobe& lobe = out.lobes[k];
        lobe.mesh = std::move(shapes[kept[k]].mesh);
        SimplifyOptions simplify;
        simplify.tolerance = o.simplify_tolerance;
        simplify.max_faces = lobe_face_budget(lobe.mesh.area(), total_area, o);
        simplify.min_faces = o.min_lobe_faces;
        simplify_closed_mesh(lobe.mesh, simplify);  // false = kept as it is (still closed)
        lobe.seed_node = new_index[cluster.seed_node];
        lobe.seed_direction = seed_direction(tree, cluster, points);
        lobe.points = cluster.points.size();
        lobe.leaf_share = leaf_share(cloud, o.leaf_label_attribute, cluster.points);
        lobe.cluster_points.reserve(cluster.points.size());
        for (int i : cluster.points) lobe.cluster_points.push_back(points[i]);
    });
    report.dropped_points_attached = attach_dropped_points(cloud, r.point_internode, out.lobes, static_cast<float>(o.dropped_point_reach));
    for (const Lobe& lobe : out.lobes) report.lobe_points += lobe.points;
    for (int u : r.point_internode) report.main_points += u >= 0 ? 1 : 0;
    report.main_points -= report.lobe_points;
    clock.mark("simplification");
    if (report_out) *report_out = std::move(report);
    return out;
}

}  // namespace treelobes::lobes
