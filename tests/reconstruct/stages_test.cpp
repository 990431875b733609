// Cleaning, tree base, stem fit, "not a tree" check and the whole single-tree pipeline on
// synthetic clouds.
#include "core/error.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/neighbour_graph.hpp"
#include "geometry/ransac_fit.hpp"
#include "reconstruct/preprocess.hpp"
#include "reconstruct/reconstruct_tree.hpp"
#include "reconstruct/tree_base.hpp"
#include "reconstruct/tree_quality.hpp"
#include "support/synthetic_clouds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

using namespace treelobes;
using test::Segment;

namespace {

// A flat ground disc of radius `r` at z = 0 with a point every `step` metres.
void add_ground(std::vector<Eigen::Vector3f>& p, float r, float step) {
    for (float x = -r; x <= r; x += step)
        for (float y = -r; y <= r; y += step)
            if (x * x + y * y <= r * r) p.push_back({x, y, 0.0f});
}

// Walls and a roof of a 6 x 5 x 3 m box, points every 5 cm.
PointCloud house() {
    PointCloud c;
    for (float a = 0; a <= 6; a += 0.05f)
        for (float z = 0; z <= 3; z += 0.05f) {
            c.positions.push_back({a, 0, z});
            c.positions.push_back({a, 5, z});
        }
    for (float b = 0; b <= 5; b += 0.05f)
        for (float z = 0; z <= 3; z += 0.05f) {
            c.positions.push_back({0, b, z});
            c.positions.push_back({6, b, z});
        }
    for (float a = 0; a <= 6; a += 0.05f)
        for (float b = 0; b <= 5; b += 0.05f) c.positions.push_back({a, b, 3.0f});
    return c;
}

// An airborne crown: an ellipsoid of horizontal radius `radius` and half height 5 m whose
// returns lie in the scan's vertical planes, lines `line_spacing` apart across the flight
// direction, a pulse every `pulse_spacing` along each, one to three returns per pulse at depths
// through the crown below it.
PointCloud airborne_crown(float radius, float line_spacing, float pulse_spacing) {
    PointCloud c;
    std::mt19937 random(7);
    const Eigen::Vector2f across = Eigen::Vector2f(0.9f, 0.44f).normalized();  // normal of the scan-line planes
    const Eigen::Vector2f along(-across.y(), across.x());
    for (float line = -radius; line <= radius; line += line_spacing)
        for (float t = -radius; t <= radius; t += pulse_spacing) {
            const Eigen::Vector2f xy = line * across + t * along;
            const float inside = 1.0f - xy.squaredNorm() / (radius * radius);
            if (inside <= 0.0f) continue;
            const float half_depth = 5.0f * std::sqrt(inside);  // the crown's half height over this point
            const int returns = 1 + static_cast<int>(random() % 3);
            for (int r = 0; r < returns; ++r) {
                const float depth = 2.0f * half_depth * static_cast<float>(random() % 1000) / 1000.0f;
                c.positions.push_back({xy.x(), xy.y(), 15.0f + half_depth - depth});
            }
        }
    return c;
}

}  // namespace

TEST(Preprocess, DuplicatesOutliersAndMapping) {
    PointCloud cloud = test::cloud_from({{{0, 0, 0}, {0, 0, 2}, 0.1f}}, 2000);
    const std::size_t n = cloud.size();
    cloud.positions.push_back(cloud.positions[5]);  // exact duplicate
    cloud.positions.push_back({5.0f, 5.0f, 1.0f});  // far outlier
    PreprocessOptions o;
    o.ground = GroundMode::Keep;
    const Preprocessed p = preprocess_cloud(cloud, o);
    EXPECT_EQ(p.duplicates, 1u);
    EXPECT_GE(p.outliers, 1u);
    EXPECT_EQ(p.point_of_input[n], p.point_of_input[5]);  // the duplicate stands for point 5
    EXPECT_EQ(p.point_of_input[n + 1], -1);               // the outlier is gone
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (p.point_of_input[i] >= 0 && i != n) {
            EXPECT_EQ(p.points[p.point_of_input[i]], cloud.positions[i]);
        }
    PointCloud tiny;
    tiny.positions.resize(3);
    EXPECT_THROW(preprocess_cloud(tiny, o), Error);
}

TEST(Preprocess, GroundPlaneIsRemovedButACutStemIsNot) {
    PointCloud scan = test::cloud_from({{{0, 0, 0}, {0, 0, 4}, 0.15f}}, 2000);
    add_ground(scan.positions, 2.0f, 0.05f);
    const Preprocessed p = preprocess_cloud(scan, {});
    EXPECT_TRUE(p.ground_found);
    EXPECT_GT(p.ground, 4000u);
    for (const auto& q : p.points) EXPECT_GT(q.z(), 0.05f);
    // A felled stem scanned with its cut face (a 0.3 m disc) has no ground to remove.
    PointCloud stem = test::cloud_from({{{0, 0, 0}, {0, 0, 4}, 0.15f}}, 2000);
    add_ground(stem.positions, 0.15f, 0.01f);
    EXPECT_FALSE(preprocess_cloud(stem, {}).ground_found);
    EXPECT_THROW(parse_ground_mode("sometimes"), Error);
}

// The table handed on to the skeleton is read from the outlier filter's query through the
// removals; it must list the same nearest kept points as a fresh query over the kept points
// (the order among equally distant points may differ).
TEST(Preprocess, HandedOnTableMatchesAFreshQuery) {
    PointCloud scan = test::cloud_from({{{0, 0, 0}, {0, 0, 4}, 0.15f}, {{0, 0, 2}, {1, 0, 3}, 0.05f}}, 2000);
    add_ground(scan.positions, 2.0f, 0.05f);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> spread(-1.5f, 1.5f);
    for (int i = 0; i < 40; ++i) scan.positions.push_back({spread(rng), spread(rng), 2.0f + spread(rng)});  // stray points
    PreprocessOptions o;
    o.table_width = 20;
    const Preprocessed p = preprocess_cloud(scan, o);
    ASSERT_TRUE(p.ground_found);
    ASSERT_GT(p.outliers, 0u);
    ASSERT_TRUE(p.index && p.neighbours);
    ASSERT_EQ(p.index->size(), p.points.size());
    const KnnTable fresh = knn_of_all_points(KdTree(p.points), 20);
    const KnnTable& given = *p.neighbours;
    ASSERT_EQ(given.k, 20);
    ASSERT_EQ(given.indices.size(), fresh.indices.size());
    for (std::size_t i = 0; i < p.points.size(); ++i) {
        const float* d_given = given.row_distances(i);
        const float* d_fresh = fresh.row_distances(i);
        std::vector<int> inner_given, inner_fresh;  // neighbours closer than the last column
        for (int j = 0; j < 20; ++j) {
            ASSERT_EQ(d_given[j], d_fresh[j]) << "row " << i;
            if (d_given[j] < d_given[19]) inner_given.push_back(given.row(i)[j]), inner_fresh.push_back(fresh.row(i)[j]);
        }
        std::sort(inner_given.begin(), inner_given.end());
        std::sort(inner_fresh.begin(), inner_fresh.end());
        ASSERT_EQ(inner_given, inner_fresh) << "row " << i;
    }
}

TEST(TreeBase, HangingBranchTipIsNotTheRoot) {
    // A stem from z = 0.3 m and a drooping branch whose tip reaches z = 0.2 m, 1.5 m away.
    const std::vector<Segment> parts{{{0, 0, 0.3f}, {0, 0, 3}, 0.1f}, {{0, 0, 2.5f}, {1.5f, 0, 0.2f}, 0.02f}};
    const PointCloud cloud = test::cloud_from(parts, 3000);
    const NeighbourGraph graph = build_neighbour_graph(cloud.positions, {});
    const TreeBase base = find_tree_base(cloud.positions, graph);
    EXPECT_TRUE(base.stem_visible);
    EXPECT_LT(base.position.head<2>().norm(), 0.05f);
    EXPECT_NEAR(base.position.z(), 0.3f, 0.05f);
    EXPECT_FALSE(base.sources.empty());
}

// An old oak or fig, 24 m tall, flares to 1.3 m of radius at its foot (the synthetic ones of
// `synth tree` do). Its foot is still the stem, not the tip of a branch hanging to the ground
// 4 m away.
TEST(TreeBase, AFlaredFootWiderThanAMetreIsTheStem) {
    const std::vector<Segment> parts{{{0, 0, 0}, {0, 0, 3}, 1.3f}, {{0, 0, 3}, {0, 0, 24}, 0.2f}, {{0, 0, 2.5f}, {4.0f, 0, 0.05f}, 0.02f}};
    const PointCloud cloud = test::cloud_from(parts, 600);
    const NeighbourGraph graph = build_neighbour_graph(cloud.positions, {});
    const TreeBase base = find_tree_base(cloud.positions, graph);
    EXPECT_TRUE(base.stem_visible);
    EXPECT_LT(base.position.head<2>().norm(), 0.1f);
    EXPECT_NEAR(base.foot_radius, 1.3f, 0.05f);
}

TEST(ReconstructTree, StemFitRadiiAndSummary) {
    // A leaning stem of radius 0.2 m with a branch; the scan sees it all round.
    const std::vector<Segment> parts{{{0, 0, 0}, {0.3f, 0, 4}, 0.2f}, {{0.15f, 0, 2}, {1.5f, 0, 3}, 0.05f}};
    PointCloud cloud = test::cloud_from(parts, 2500);
    cloud.origin = {600000.0, 6000000.0, 50.0};
    ReconstructOptions o;
    const TreeReconstruction r = reconstruct_tree(cloud, o, "leaning");
    const TreeSummary& s = r.summary;
    ASSERT_TRUE(s.dbh_fitted);
    EXPECT_NEAR(s.dbh, 0.4f, 0.03f);
    EXPECT_EQ(s.root_diameter_source, "base fit");
    EXPECT_NEAR(s.root_diameter, 0.4f, 0.04f);
    EXPECT_NEAR(r.skeleton.nodes[0].radius, 0.5f * s.root_diameter, 1e-6f);
    // Top of the bark at 4.0 m + 0.2 m x sin(4.3 deg), foot 0.015 m below z = 0.
    EXPECT_NEAR(s.height, 4.03f, 0.05f);
    EXPECT_EQ(s.branches, 2u);
    EXPECT_FALSE(s.quality.not_a_tree);
    EXPECT_TRUE(s.stem_visible);
    EXPECT_EQ(r.skeleton.origin, cloud.origin);
    EXPECT_EQ(r.point_internode.size(), cloud.size());
    // Radii never grow towards the tips (Eq. 1 with subtree lengths).
    for (std::size_t i = 1; i < r.skeleton.size(); ++i)
        EXPECT_LE(r.skeleton.nodes[i].radius, r.skeleton.nodes[r.skeleton.nodes[i].parent].radius + 1e-6f);
    // A given root diameter wins.
    o.root_diameter = 0.5;
    EXPECT_NEAR(reconstruct_tree(cloud, o).summary.root_diameter, 0.5f, 1e-6f);
}

// An airborne crown: foliage 8-12 m up and no stem. Given the stem's foot, the skeleton starts
// there and climbs a hidden trunk to the crown; heights and the guessed root diameter are
// measured from the foot, and no scan point is put on the trunk.
TEST(ReconstructTree, AnAirborneCrownIsJoinedToItsStemFoot) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    PointCloud crown;
    while (crown.size() < 4000) {
        const Eigen::Vector3f p(u(rng), u(rng), u(rng));
        if (p.norm() <= 1.0f) crown.positions.push_back({2.0f * p.x(), 2.0f * p.y(), 10.0f + 2.0f * p.z()});
    }
    ReconstructOptions o;
    const TreeReconstruction floating = reconstruct_tree(crown, o, "crown");
    ASSERT_FALSE(floating.summary.stem_visible);
    EXPECT_GT(floating.skeleton.nodes[0].position.z(), 7.5f);
    EXPECT_EQ(floating.summary.hidden_trunk_nodes, 0u);

    o.hidden_stem_foot = Eigen::Vector3f(0.1f, 0, 0);
    const TreeReconstruction r = reconstruct_tree(crown, o, "crown");
    const TreeSummary& s = r.summary;
    EXPECT_GT(s.hidden_trunk_nodes, 10u);
    EXPECT_EQ(r.skeleton.nodes[0].position, *o.hidden_stem_foot);
    EXPECT_NEAR(s.height, 12.0f, 0.1f);
    EXPECT_EQ(s.root_diameter_source, "height / 50");
    EXPECT_NEAR(s.root_diameter, s.height / 50.0f, 1e-6f);
    int lowest_internode = static_cast<int>(r.skeleton.size());  // of the crown's points
    for (int v : r.point_internode)
        if (v >= 0) lowest_internode = std::min(lowest_internode, v);
    EXPECT_GT(lowest_internode, static_cast<int>(s.hidden_trunk_nodes));  // no scan point on the trunk
    EXPECT_GT(r.skeleton.total_length(), floating.skeleton.total_length() + 7.0f);
}

TEST(TreeQuality, HouseIsNotATreeButATreeIs) {
    const QualityReport h = assess_planarity(house().positions);
    EXPECT_TRUE(h.not_a_tree);
    EXPECT_GE(h.wide_planes, 2);
    const QualityReport t = assess_planarity(test::cloud_from(test::y_tree(), 3000).positions);
    EXPECT_FALSE(t.not_a_tree);
    EXPECT_LT(t.planar_fraction, 0.1f);
}

// The scan lines of a sparse airborne crown are vertical sheets of returns 10 m wide with
// nothing within 0.1 m of them, but their neighbours lie a line spacing away, nearer than the
// returns within a sheet lie to each other: no wall. (lidR's Megaplot gave ten such "roofs".)
TEST(TreeQuality, TheScanLinesOfASparseAirborneCrownAreNoWalls) {
    const PointCloud crown = airborne_crown(4.0f, 0.7f, 0.7f);  // about 1.5 returns per square metre
    ASSERT_GT(crown.size(), 80u);
    ASSERT_LT(crown.size(), 200u);
    const QualityReport r = assess_planarity(crown.positions);
    EXPECT_FALSE(r.not_a_tree) << r.planar_fraction;
    EXPECT_EQ(r.wide_planes, 0);
}

// A narrow crown crossed by three scan lines, each a sheet of returns with no other line within
// its points' spacing: as walls they would hold half the crown. In an airborne scan such sparse
// steep planes are not judged (idtrees' crown OSBS02703 was such a "building").
TEST(TreeQuality, AnAirborneScanJudgesItsRoofsNotItsSteepPlanes) {
    const PointCloud crown = airborne_crown(1.7f, 1.1f, 0.25f);
    QualityOptions airborne;
    airborne.airborne = true;
    const QualityReport r = assess_planarity(crown.positions, airborne);
    EXPECT_FALSE(r.not_a_tree) << r.planar_fraction;
    // A building seen from above: its roof and returns down one wall, which counts as a face too.
    PointCloud building;
    for (float a = 0; a <= 8; a += 0.5f)
        for (float b = 0; b <= 6; b += 0.5f) building.positions.push_back({a, b, 6.0f});
    for (float a = 0; a <= 8; a += 0.5f)
        for (float z = 1; z < 6; z += 1.0f) building.positions.push_back({a, 0, z});
    const QualityReport b = assess_planarity(building.positions, airborne);
    EXPECT_TRUE(b.not_a_tree) << b.planar_fraction;
    EXPECT_EQ(b.wide_planes, 2);
}
