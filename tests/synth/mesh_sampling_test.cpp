// Wood/leaf labels of CG tree models (by name, by user leaf names, by geometry) and their
// samples: exact counts, area weighting, determinism, scans of a mesh through the scanner.
#include "core/mesh_io.hpp"
#include "support/test_support.hpp"
#include "synth/mesh_labels.hpp"
#include "synth/mesh_sampling.hpp"
#include "synth/tree_mesh.hpp"
#include "config/species_profile.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace treelobes;
using namespace treelobes::synth;

namespace {

NamedMesh fixture_tree() { return read_named_mesh(test::source_dir() / "tests/synth/fixtures/small_tree.obj"); }

// A closed square tube (wood) along z and `leaves` small flat quads around it, without names.
NamedMesh tube_with_leaves(int leaves) {
    NamedMesh m;
    TriangleMesh& mesh = m.mesh;
    const int sides = 8, rings = 6;
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < sides; ++s) {
            const double a = 2 * M_PI * s / sides;
            mesh.vertices.emplace_back(0.1f * static_cast<float>(std::cos(a)), 0.1f * static_cast<float>(std::sin(a)), 0.5f * r);
        }
    for (int r = 0; r + 1 < rings; ++r)
        for (int s = 0; s < sides; ++s) {
            const int a = r * sides + s, b = r * sides + (s + 1) % sides, c = a + sides, d = b + sides;
            mesh.faces.push_back({a, b, d});
            mesh.faces.push_back({a, d, c});
        }
    for (int k = 0; k < leaves; ++k) {
        const int base = static_cast<int>(mesh.vertices.size());
        const float z = 0.5f + 0.02f * k, x = 0.3f + 0.01f * (k % 7);
        mesh.vertices.emplace_back(x, 0.0f, z);
        mesh.vertices.emplace_back(x + 0.05f, 0.0f, z);
        mesh.vertices.emplace_back(x + 0.05f, 0.02f, z + 0.03f);
        mesh.vertices.emplace_back(x, 0.02f, z + 0.03f);
        mesh.faces.push_back({base, base + 1, base + 2});
        mesh.faces.push_back({base, base + 2, base + 3});
    }
    return m;
}

// Two unit-spaced squares: area 1 (wood) and area 3 (leaf).
TriangleMesh two_squares() {
    TriangleMesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}, {5, 0, 0}, {5, 1, 0}, {2, 1, 0}};
    m.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    return m;
}

}  // namespace

TEST(MeshLabels, NamesDecideMaterialThenGroup) {
    const NamedMesh tree = fixture_tree();
    ASSERT_EQ(tree.mesh.faces.size(), 34u);
    EXPECT_EQ(tree.report.degenerate_faces, 1u);
    MeshLabelReport report;
    const std::vector<std::uint8_t> wood = label_faces(tree, {}, &report);
    EXPECT_EQ(report.wood_by_name, 20u);     // trunk (material), branch (group "Branch01")
    EXPECT_EQ(report.leaf_by_name, 9u);      // leaves (material), needles (group)
    EXPECT_EQ(report.leaf_by_geometry, 1u);  // the flat triangle of Part2
    EXPECT_EQ(report.wood_by_geometry, 4u);  // the small solid of Part2
    EXPECT_EQ(report.parts, 2u);
    for (std::size_t f = 0; f < 12; ++f) EXPECT_EQ(wood[f], 1) << f;
    for (std::size_t f = 20; f < 29; ++f) EXPECT_EQ(wood[f], 0) << f;
    EXPECT_EQ(wood[29], 0);
    EXPECT_GT(report.wood_area, 6.7);
}

TEST(MeshLabels, UserLeafNamesOverrideAndOtherNamedFacesAreWood) {
    MeshLabelOptions options;
    options.leaf_words = parse_word_list(" NEEDLE , ");
    options.named_faces_default_to_wood = true;
    ASSERT_EQ(options.leaf_words, std::vector<std::string>{"needle"});
    MeshLabelReport report;
    const std::vector<std::uint8_t> wood = label_faces(fixture_tree(), options, &report);
    EXPECT_EQ(report.leaf_by_name, 2u);
    EXPECT_EQ(report.wood_by_name, 32u);
    EXPECT_EQ(report.leaf_by_geometry + report.wood_by_geometry, 0u);
    EXPECT_EQ(wood[20], 1);  // Leaves_Summer is not a leaf name any more
}

TEST(MeshLabels, GeometryTellsSmallFlatLeavesFromTubes) {
    const NamedMesh m = tube_with_leaves(40);
    MeshLabelReport report;
    const std::vector<std::uint8_t> wood = label_faces(m, {}, &report);
    EXPECT_EQ(report.parts, 41u);
    EXPECT_EQ(report.leaf_parts, 40u);
    EXPECT_EQ(report.wood_by_geometry, 80u);
    EXPECT_EQ(report.leaf_by_geometry, 80u);
    for (std::size_t f = 0; f < 80; ++f) EXPECT_EQ(wood[f], 1);
    for (std::size_t f = 80; f < wood.size(); ++f) EXPECT_EQ(wood[f], 0);

    // Leaves must be small as well as flat: under a tiny area bound no part is a leaf.
    MeshLabelOptions strict;
    strict.max_leaf_area_fraction = 1e-6;
    label_faces(m, strict, &report);
    EXPECT_EQ(report.leaf_by_geometry, 0u);
}

TEST(MeshLabels, GeometryAgreesWithTheMaterialsOfSyntheticTrees) {
    // Palm (long curved frond stalks, whose vertices lie nearly in a plane) and birch (thin twigs).
    const auto profiles = load_species_profiles(default_species_file());
    for (const char* name : {"palm", "birch"}) {
        GrowOptions grow;
        grow.max_leaves = 3000;
        grow.height_m = 6;
        const TreeMesh tree = tree_mesh(synth::grow(find_species_profile(profiles, name), 3, grow));
        const std::vector<std::uint8_t> by_name = label_faces(tree.named());
        NamedMesh unnamed;
        unnamed.mesh = tree.combined();
        MeshLabelReport report;
        const std::vector<std::uint8_t> by_geometry = label_faces(unnamed, {}, &report);
        ASSERT_EQ(by_geometry.size(), by_name.size());
        std::size_t disagree = 0;
        for (std::size_t f = 0; f < by_name.size(); ++f) disagree += by_name[f] != by_geometry[f];
        EXPECT_EQ(disagree, 0u) << name;
        EXPECT_EQ(report.leaf_by_geometry, tree.leaves.faces.size()) << name;
    }
}

TEST(MeshSampling, UniformGivesTheCountWeightedByArea) {
    const TriangleMesh m = two_squares();
    const std::vector<std::uint8_t> wood{1, 1, 0, 0};
    MeshSamplingOptions options;
    options.samples = 4000;
    MeshSamplingReport report;
    const PointCloud cloud = sample_mesh(m, wood, options, &report);
    ASSERT_EQ(cloud.size(), 4000u);
    EXPECT_NEAR(report.surface_area, 4.0, 1e-9);
    // Stratified along the area: each square gets its share up to one point.
    EXPECT_NEAR(static_cast<double>(report.wood_points), 1000.0, 1.0);
    EXPECT_EQ(report.wood_points + report.leaf_points, 4000u);
    const ExtraAttribute* labels = cloud.extra("wood");
    ASSERT_NE(labels, nullptr);
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3f p = cloud.positions[i];
        EXPECT_EQ(labels->values[i] > 0.5, p.x() <= 1.0f) << i;  // labels follow the face
        EXPECT_TRUE(p.z() == 0.0f && p.y() >= 0.0f && p.y() <= 1.0f);
    }
    // Left and right halves of the big square get the same number of points, give or take noise.
    std::size_t left = 0;
    for (const auto& p : cloud.positions) left += p.x() > 2.0f && p.x() < 3.5f;
    EXPECT_NEAR(static_cast<double>(left), 1500.0, 150.0);

    options.samples = 0;
    options.density = 250;  // per m^2: 4 m^2
    EXPECT_EQ(sample_mesh(m, wood, options).size(), 1000u);
}

TEST(MeshSampling, SameSeedSameSamplesOtherSeedOthers) {
    const TriangleMesh m = two_squares();
    const std::vector<std::uint8_t> wood{1, 1, 0, 0};
    const PointCloud a = sample_surface(m, wood, 500, 7), b = sample_surface(m, wood, 500, 7), c = sample_surface(m, wood, 500, 8);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_NE(a.positions, c.positions);
}

TEST(MeshSampling, ScansSeeTheModelAndKeepLabels) {
    const NamedMesh tree = fixture_tree();
    const std::vector<std::uint8_t> wood = label_faces(tree);
    MeshSamplingOptions options;
    options.samples = 3000;
    options.pattern = SamplePattern::Tls;
    MeshSamplingReport report;
    const PointCloud tls = sample_mesh(tree.mesh, wood, options, &report);
    EXPECT_GT(tls.size(), 1500u);
    EXPECT_LE(tls.size(), 3000u);
    EXPECT_GT(report.pulses, 0u);
    EXPECT_GT(report.wood_points, 0u);
    ASSERT_NE(tls.extra("wood"), nullptr);
    EXPECT_EQ(tls.extra("treeID"), nullptr);
    EXPECT_EQ(tls.origin, tree.mesh.origin);
    // On the surface: every scanned point lies within range noise of the model's box.
    for (const auto& p : tls.positions) EXPECT_TRUE(p.z() > -0.05f && p.z() < 4.4f) << p.transpose();
    EXPECT_EQ(sample_mesh(tree.mesh, wood, options).positions, tls.positions);

    options.pattern = SamplePattern::Als;
    const PointCloud als = sample_mesh(tree.mesh, wood, options);
    EXPECT_GT(als.size(), 100u);
}

TEST(MeshSampling, BadInputAndOptions) {
    TriangleMesh empty;
    EXPECT_EQ(test::error_code_of([&] { sample_mesh(empty, {}, {}); }), ExitCode::InvalidInput);
    TriangleMesh flat;
    flat.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    flat.faces = {{0, 1, 2}};
    EXPECT_EQ(test::error_code_of([&] { sample_mesh(flat, {1}, {}); }), ExitCode::InvalidInput);
    MeshSamplingOptions few;
    few.samples = 10;
    EXPECT_EQ(test::error_code_of([&] { sample_mesh(two_squares(), {1, 1, 0, 0}, few); }), ExitCode::Usage);
    EXPECT_EQ(test::error_code_of([] { parse_sample_pattern("lidar"); }), ExitCode::Usage);
}
