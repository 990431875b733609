#include "reconstruct/tree_base.hpp"

#include "core/error.hpp"
#include "geometry/ransac_fit.hpp"
#include "geometry/union_find.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace treelobes {

namespace {

struct Piece {
    std::vector<int> members;
    float z_min = std::numeric_limits<float>::infinity();
};

// Connected pieces of the points below `z_limit`, using graph edges between such points.
std::vector<Piece> bottom_pieces(std::span<const Eigen::Vector3f> points, const NeighbourGraph& graph, float z_limit) {
    const int n = static_cast<int>(points.size());
    UnionFind sets(points.size());
    for (int i = 0; i < n; ++i) {
        if (points[i].z() >= z_limit) continue;
        for (std::uint32_t e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e)
            if (points[graph.targets[e]].z() < z_limit) sets.unite(i, graph.targets[e]);
    }
    std::vector<int> piece_of(points.size(), -1);
    std::vector<Piece> pieces;
    for (int i = 0; i < n; ++i) {
        if (points[i].z() >= z_limit) continue;
        const int root = sets.find(i);
        if (piece_of[root] < 0) {
            piece_of[root] = static_cast<int>(pieces.size());
            pieces.emplace_back();
        }
        Piece& piece = pieces[piece_of[root]];
        piece.members.push_back(i);
        piece.z_min = std::min(piece.z_min, points[i].z());
    }
    return pieces;
}

float horizontal_radius(std::span<const Eigen::Vector3f> points, const std::vector<int>& members, const Eigen::Vector2f& centre) {
    std::vector<float> r;
    for (int i : members) r.push_back((points[i].head<2>() - centre).norm());
    std::sort(r.begin(), r.end());
    return r[r.size() * 9 / 10];  // 90th percentile: robust to a few stray points
}

}  // namespace

TreeBase find_tree_base(std::span<const Eigen::Vector3f> points, const NeighbourGraph& graph, const TreeBaseOptions& o) {
    if (points.empty() || graph.vertex_count() != points.size())
        throw Error(ExitCode::Internal, "find_tree_base: the graph does not match the points");
    float z_low = std::numeric_limits<float>::infinity(), z_high = -z_low;
    for (const auto& p : points) {
        z_low = std::min(z_low, p.z());
        z_high = std::max(z_high, p.z());
    }
    const float slab = o.slab_height > 0 ? o.slab_height : std::clamp(0.03f * (z_high - z_low), 0.2f, 0.6f);
    const float max_stem_radius = std::max(o.max_stem_radius, o.max_stem_radius_per_height * (z_high - z_low));
    std::vector<Piece> pieces = bottom_pieces(points, graph, z_low + slab);
    TreeBase base;
    base.bottom_pieces = pieces.size();
    // The stem is the biggest narrow piece (lowest first on ties): hanging twigs are small, and
    // ground clutter left after ground removal is wide. With no narrow piece the biggest one
    // stands for the (hidden) stem.
    auto bigger = [](const Piece& a, const Piece& b) {
        if (a.members.size() != b.members.size()) return a.members.size() > b.members.size();
        return a.z_min < b.z_min;
    };
    std::vector<bool> narrow(pieces.size());
    std::vector<float> piece_radius(pieces.size());
    std::vector<Eigen::Vector2f> piece_mean(pieces.size());
    for (std::size_t k = 0; k < pieces.size(); ++k) {
        Eigen::Vector2f mean = Eigen::Vector2f::Zero();
        for (int i : pieces[k].members) mean += points[i].head<2>();
        mean /= static_cast<float>(pieces[k].members.size());
        piece_mean[k] = mean;
        piece_radius[k] = horizontal_radius(points, pieces[k].members, mean);
        narrow[k] = pieces[k].members.size() >= 10 && piece_radius[k] <= max_stem_radius;
    }
    std::size_t pick = 0;
    bool any_narrow = false;
    for (std::size_t k = 0; k < pieces.size(); ++k) {
        if (narrow[k] && (!any_narrow || bigger(pieces[k], pieces[pick])))
            pick = k;
        else if (!narrow[k] && !any_narrow && bigger(pieces[k], pieces[pick]))
            pick = k;
        any_narrow |= narrow[k];
    }
    const Piece& stem = pieces[pick];

    std::vector<Eigen::Vector2f> foot_xy;
    Eigen::Vector2f centroid = Eigen::Vector2f::Zero();
    for (int i : stem.members)
        if (points[i].z() < stem.z_min + o.foot_height) {
            base.sources.push_back(i);
            foot_xy.push_back(points[i].head<2>());
            centroid += points[i].head<2>();
        }
    centroid /= static_cast<float>(foot_xy.size());

    // Circle through the lower part of the stem piece (more points than the foot alone).
    std::vector<Eigen::Vector2f> lower_xy;
    for (int i : stem.members)
        if (points[i].z() < stem.z_min + std::max(o.foot_height, 0.5f * slab)) lower_xy.push_back(points[i].head<2>());
    const CircleFit circle = fit_circle(lower_xy, 0.02f, 0.01f, max_stem_radius);
    // A circle wider than the piece itself was fitted to clutter at the foot (ground left over).
    // Without a trusted circle the centre of the whole piece is nearer the stem axis than the
    // centroid of its lowest points (which may be that clutter).
    Eigen::Vector2f centre = piece_mean[pick];
    if (circle.ok && circle.coverage >= 0.25f && (circle.centre - centroid).norm() <= circle.radius + 0.05f &&
        circle.radius <= 1.2f * piece_radius[pick]) {
        centre = circle.centre;
        base.circle_fitted = true;
        base.foot_radius = circle.radius;
    }
    base.stem_visible = narrow[pick];
    base.position = Eigen::Vector3f(centre.x(), centre.y(), stem.z_min);
    std::sort(base.sources.begin(), base.sources.end());
    return base;
}

}  // namespace treelobes
