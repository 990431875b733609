#include "segment/terrestrial_paths.hpp"

#include "geometry/kd_tree.hpp"
#include "geometry/neighbour_graph.hpp"
#include "geometry/shortest_paths.hpp"
#include "geometry/union_find.hpp"
#include "segment/terrestrial_stems.hpp"
#include "segment/tree_labels.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace treelobes {

namespace {

// Vegetation points thinned to a voxel grid: the graph is built on one point per voxel (the mean
// of its points) and every point takes its voxel's label.
struct Voxels {
    std::vector<Eigen::Vector3f> centres;
    std::vector<int> voxel_of_point;  // -1 for points outside the graph
};

Voxels voxelise(const PointCloud& cloud, const std::vector<std::uint8_t>& vegetation, float size) {
    Voxels voxels;
    voxels.voxel_of_point.assign(cloud.size(), -1);
    std::unordered_map<std::uint64_t, int> index;
    std::vector<Eigen::Vector3d> sums;
    std::vector<std::uint32_t> counts;
    const auto key_part = [size](float v) {
        return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v / size)) & 0x1FFFFF);
    };
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (!vegetation[i]) continue;
        const Eigen::Vector3f& p = cloud.positions[i];
        const std::uint64_t key = key_part(p.x()) | key_part(p.y()) << 21 | key_part(p.z()) << 42;
        const auto [it, added] = index.emplace(key, static_cast<int>(sums.size()));
        if (added) {
            sums.emplace_back(0, 0, 0);
            counts.push_back(0);
        }
        sums[static_cast<std::size_t>(it->second)] += p.cast<double>();
        ++counts[static_cast<std::size_t>(it->second)];
        voxels.voxel_of_point[i] = it->second;
    }
    voxels.centres.reserve(sums.size());
    for (std::size_t v = 0; v < sums.size(); ++v) voxels.centres.push_back((sums[v] / counts[v]).cast<float>());
    return voxels;
}

// What the paths from each source cost per unit of the horizontal part of their edges' weights:
// (median stem radius / the source's stem radius)^exponent. A thick trunk carries a wide crown
// (crown width grows with the stem diameter), so its paths reach farther sideways than a thin
// neighbour's: the far limbs of a broad crown that reach over a small tree stay with their trunk
// instead of going to the stem that is nearer through the mixed branches (a multiplicatively
// weighted partition, Aurenhammer & Edelsbrunner 1984, in the graph's metric). Climbing is not
// scaled: a thin tree reaches its own top as cheaply as a thick one, whose paths would otherwise
// take the tops of tall, slender neighbours.
std::vector<float> reach_scales(const std::vector<Stem>& stems, const std::vector<int>& source_stem, float exponent) {
    std::vector<float> radii;
    for (const Stem& stem : stems) radii.push_back(stem.radius);
    std::nth_element(radii.begin(), radii.begin() + static_cast<std::ptrdiff_t>(radii.size() / 2), radii.end());
    const float median_radius = radii[radii.size() / 2];
    std::vector<float> scales;
    scales.reserve(source_stem.size());
    for (int s : source_stem) scales.push_back(std::pow(median_radius / stems[static_cast<std::size_t>(s)].radius, exponent));
    return scales;
}

// Per edge of the graph, the horizontal share of its squared length: the part of its cost a
// stem's reach scales (a thick trunk's crown spreads wider, not higher).
std::vector<float> horizontal_shares(const NeighbourGraph& graph, const std::vector<Eigen::Vector3f>& positions) {
    std::vector<float> shares(graph.targets.size(), 0.0f);
    for (std::size_t u = 0; u + 1 < graph.offsets.size(); ++u)
        for (std::uint32_t e = graph.offsets[u]; e < graph.offsets[u + 1]; ++e) {
            const Eigen::Vector3f step = positions[static_cast<std::size_t>(graph.targets[e])] - positions[u];
            const float squared = step.squaredNorm();
            if (squared > 0.0f) shares[e] = std::clamp(step.head<2>().squaredNorm() / squared, 0.0f, 1.0f);
        }
    return shares;
}

// Lowest height above ground of each voxel's points.
std::vector<float> voxel_floors(const Voxels& voxels, const Terrain& terrain) {
    std::vector<float> floors(voxels.centres.size(), std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < voxels.voxel_of_point.size(); ++i) {
        const int v = voxels.voxel_of_point[i];
        if (v >= 0) floors[static_cast<std::size_t>(v)] = std::min(floors[static_cast<std::size_t>(v)], terrain.height_above_ground[i]);
    }
    return floors;
}

// Pieces of crown the paths do not reach join the tree nearest to them. The graph links each
// voxel to its k nearest only, so a sparse treetop or a tier of a tiered crown whose nearest
// voxels are all its own is a piece apart even within max_gap of the crown below it: on the
// synthetic terrestrial plots 25,000 tree points per plot stayed 0, most of them above 5 m,
// and the trees lost up to 7 m of their height. A piece that hangs in the air (its lowest point
// at least detached_min_height above the ground; understory stands on it) and has at least
// min_detached_voxels voxels (a stray return has one) takes the tree of the nearest labelled
// voxel within attach_gap; pieces attached in one round are labelled for the next, so a chain
// of pieces up a sparse top joins link by link.
void attach_detached_pieces(const NeighbourGraph& graph, const std::vector<Eigen::Vector3f>& centres, const std::vector<float>& floors,
                            const SegmentOptions& options, std::vector<int>& voxel_tree) {
    std::size_t piece_count = 0;
    const std::vector<int> piece = connected_components(graph, &piece_count);
    std::vector<std::vector<int>> unlabelled(piece_count);
    std::vector<float> piece_floor(piece_count, std::numeric_limits<float>::infinity());
    for (std::size_t v = 0; v < centres.size(); ++v) {
        if (voxel_tree[v] >= 0) continue;
        const auto p = static_cast<std::size_t>(piece[v]);
        unlabelled[p].push_back(static_cast<int>(v));
        piece_floor[p] = std::min(piece_floor[p], floors[v]);
    }
    std::vector<std::size_t> waiting;
    for (std::size_t p = 0; p < piece_count; ++p)
        if (unlabelled[p].size() >= static_cast<std::size_t>(options.min_detached_voxels) && piece_floor[p] >= options.detached_min_height)
            waiting.push_back(p);
    const float reach_squared = options.attach_gap * options.attach_gap;
    while (!waiting.empty()) {
        std::vector<Eigen::Vector3f> labelled_centres;
        std::vector<int> labelled_tree;
        for (std::size_t v = 0; v < centres.size(); ++v)
            if (voxel_tree[v] >= 0) {
                labelled_centres.push_back(centres[v]);
                labelled_tree.push_back(voxel_tree[v]);
            }
        if (labelled_centres.empty()) return;
        const KdTree labelled(labelled_centres);
        std::vector<std::pair<std::size_t, int>> joins;  // piece, tree
        std::vector<std::size_t> still_waiting;
        for (std::size_t p : waiting) {
            float best = reach_squared;
            int tree = -1;
            for (int v : unlabelled[p]) {
                float squared = 0.0f;
                const int nearest = labelled.nearest(centres[static_cast<std::size_t>(v)], &squared);
                if (squared <= best) {
                    best = squared;
                    tree = labelled_tree[static_cast<std::size_t>(nearest)];
                }
            }
            if (tree >= 0)
                joins.emplace_back(p, tree);
            else
                still_waiting.push_back(p);
        }
        if (joins.empty()) return;
        for (const auto& [p, tree] : joins)
            for (int v : unlabelled[p]) voxel_tree[static_cast<std::size_t>(v)] = tree;
        waiting = std::move(still_waiting);
    }
}

// Two trees' crowns do not share a top. A willow's curtain of hanging twigs can hold a circle of
// its trunk's size a little farther from the trunk than stem_merge_distance (1.1 m on a
// synthetic plot); the curtain's paths then take most of the crown, the trunk's the rest, and
// both regions reach the crown's top (their highest voxels 0.5 m apart). Stems closer than
// shared_top_stem_distance whose regions' highest voxels lie within shared_top_distance of each
// other are one tree's, which the stem with the most circle points keeps. Neighbours of one
// height do not meet so: on TreeLS's pine plot two pines 1.5 m apart have tops 0.7 m apart
// across but 1.6 m apart in height.
void join_trees_sharing_a_top(const std::vector<Stem>& stems, const std::vector<Eigen::Vector3f>& centres, const SegmentOptions& options,
                              std::vector<int>& voxel_tree) {
    if (options.shared_top_stem_distance <= 0.0f || stems.size() < 2) return;
    std::vector<int> highest(stems.size(), -1);
    for (std::size_t v = 0; v < voxel_tree.size(); ++v) {
        const int tree = voxel_tree[v];
        if (tree >= 0 && (highest[static_cast<std::size_t>(tree)] < 0 ||
                          centres[v].z() > centres[static_cast<std::size_t>(highest[static_cast<std::size_t>(tree)])].z()))
            highest[static_cast<std::size_t>(tree)] = static_cast<int>(v);
    }
    UnionFind joined(stems.size());
    bool any = false;
    for (std::size_t a = 0; a < stems.size(); ++a)
        for (std::size_t b = a + 1; b < stems.size(); ++b) {
            if (highest[a] < 0 || highest[b] < 0) continue;
            if ((stems[a].centre - stems[b].centre).norm() >= options.shared_top_stem_distance) continue;
            const Eigen::Vector3f& top_a = centres[static_cast<std::size_t>(highest[a])];
            const Eigen::Vector3f& top_b = centres[static_cast<std::size_t>(highest[b])];
            if ((top_a - top_b).norm() < options.shared_top_distance) any |= joined.unite(static_cast<int>(a), static_cast<int>(b));
        }
    if (!any) return;
    std::vector<int> keeper(stems.size(), -1);  // per set root: the stem with the most circle points
    for (std::size_t s = 0; s < stems.size(); ++s) {
        int& k = keeper[static_cast<std::size_t>(joined.find(static_cast<int>(s)))];
        if (k < 0 || stems[s].inliers > stems[static_cast<std::size_t>(k)].inliers) k = static_cast<int>(s);
    }
    for (int& tree : voxel_tree)
        if (tree >= 0) tree = keeper[static_cast<std::size_t>(joined.find(tree))];
}

}  // namespace

void segment_terrestrial(const PointCloud& cloud, const Terrain& terrain, const std::vector<std::uint8_t>& vegetation,
                         const SegmentOptions& options, TreeSegmentation& result) {
    const std::vector<Stem> stems = find_stems(cloud, terrain, vegetation, options);
    if (stems.empty()) return;
    const Voxels voxels = voxelise(cloud, vegetation, options.graph_voxel);

    // Every voxel of a stem's slice points is a source of that stem.
    std::vector<int> sources, source_stem;
    std::vector<std::uint8_t> is_source(voxels.centres.size(), 0);
    for (std::size_t s = 0; s < stems.size(); ++s)
        for (int i : stems[s].points) {
            const int v = voxels.voxel_of_point[static_cast<std::size_t>(i)];
            if (is_source[static_cast<std::size_t>(v)]) continue;
            is_source[static_cast<std::size_t>(v)] = 1;
            sources.push_back(v);
            source_stem.push_back(static_cast<int>(s));
        }

    NeighbourGraphOptions graph_options;
    graph_options.neighbours = std::min(options.graph_neighbours, std::max(2, static_cast<int>(voxels.centres.size()) - 1));
    graph_options.max_edge_length = options.max_gap;
    graph_options.join_components = false;  // a gap wider than max_gap separates: what lies beyond stays 0
    graph_options.beta = options.graph_beta;
    const NeighbourGraph graph = build_neighbour_graph(voxels.centres, graph_options);
    const std::vector<float> scales = reach_scales(stems, source_stem, options.stem_reach_exponent);
    const std::vector<float> shares = horizontal_shares(graph, voxels.centres);
    const ShortestPaths paths = shortest_paths(graph, sources, SourceScaling{scales, shares}, EdgeCost::Weight);

    std::vector<int> voxel_tree(voxels.centres.size(), -1);
    for (std::size_t v = 0; v < voxel_tree.size(); ++v)
        if (paths.source[v] >= 0) voxel_tree[v] = source_stem[static_cast<std::size_t>(paths.source[v])];
    if (options.attach_gap > 0.0f) attach_detached_pieces(graph, voxels.centres, voxel_floors(voxels, terrain), options, voxel_tree);
    join_trees_sharing_a_top(stems, voxels.centres, options, voxel_tree);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const int v = voxels.voxel_of_point[i];
        if (v >= 0 && voxel_tree[static_cast<std::size_t>(v)] >= 0) result.tree_id[i] = voxel_tree[static_cast<std::size_t>(v)] + 1;
    }
    std::vector<Eigen::Vector2f> stem_xy;
    std::vector<float> stem_radius;
    for (const auto& stem : stems) {
        stem_xy.push_back(stem.centre);
        stem_radius.push_back(stem.radius);
    }
    result.trees = collect_trees(cloud, terrain, result.tree_id, stems.size(), stem_xy, stem_radius, options.min_tree_height);
}

}  // namespace treelobes
