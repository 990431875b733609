// Skeleton nodes moved onto least-squares cylinder axes (reconstruct/cylinder_axes.hpp): the
// fit itself, one-sided arcs, the trust tests (flat strips, bent twigs), fixed nodes, options
// and the CLI switch.
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "reconstruct/cylinder_axes.hpp"
#include "support/synthetic_clouds.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

using namespace treelobes;

namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// Bark points of a branch along +x (0..length) with its axis on the x axis, seen over the arc
// of half-angle `half_angle` centred on the -z side (scanned from below), `per_metre` points
// per metre of branch, Gaussian noise `noise`.
std::vector<Eigen::Vector3f> lower_arc(float radius, float half_angle, float length, int per_metre, float noise, unsigned seed = 5) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> along(0.0f, length), angle(-half_angle, half_angle);
    std::normal_distribution<float> jitter(0.0f, noise);
    std::vector<Eigen::Vector3f> points;
    const int count = static_cast<int>(static_cast<float>(per_metre) * length);
    for (int i = 0; i < count; ++i) {
        const float a = angle(rng);
        // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
        // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
        const float z = -radius * std::cos(a) + jitter(rng), y = radius * std::sin(a) + jitter(rng);
        const float x = along(rng) + jitter(rng);  // along first, then its jitter (GCC's order within the sum)
        points.emplace_back(x, y, z);
    }
    return points;
}

// A chain of internodes of length `step` along the polyline `path(x)` for x in [0, length];
// every point belongs to the internode covering its x.
struct Chain {
    TreeGraph tree;
    std::vector<int> internode;
    template <class Path>
    Chain(const std::vector<Eigen::Vector3f>& points, float length, float step, Path path) {
        const int count = static_cast<int>(std::lround(length / step));
        tree.add_node(path(0.0f), 0, -1);
        for (int k = 1; k <= count; ++k) tree.add_node(path(step * static_cast<float>(k)), 0, k - 1);
        for (const auto& p : points) internode.push_back(std::clamp(static_cast<int>(std::ceil(p.x() / step)), 1, count));
    }
};

float lateral_offset(const Eigen::Vector3f& p) { return std::hypot(p.y(), p.z()); }

CylinderAxesOptions on() {
    CylinderAxesOptions o;
    o.enabled = true;
    return o;
}

}  // namespace

// The lower half of a 3 cm branch, 150 points per metre (a sparse scan), skeleton at the points'
// centroid: 1.9 cm below the axis. The cylinder fits bring the nodes onto the axis.
TEST(CylinderAxes, NodesOnAOneSidedArcMoveOntoTheAxis) {
    const float r = 0.03f, half = 0.5f * kPi;
    const auto points = lower_arc(r, half, 1.0f, 150, 0.002f);
    const float centroid_depth = r * std::sin(half) / half;
    Chain c(points, 1.0f, 0.05f, [&](float x) { return Eigen::Vector3f(x, 0.0f, -centroid_depth); });
    for (std::size_t u = 1; u < c.tree.size(); ++u) ASSERT_GT(lateral_offset(c.tree.nodes[u].position), 0.018f);
    CylinderAxesOptions off;  // the default: off
    EXPECT_EQ(fit_cylinder_axes(c.tree, points, c.internode, off), 0u);
    EXPECT_EQ(c.tree.nodes[5].position.z(), -centroid_depth);
    EXPECT_EQ(fit_cylinder_axes(c.tree, points, c.internode, on()), c.tree.size() - 1);
    EXPECT_EQ(c.tree.nodes[0].position.z(), -centroid_depth);  // the root stays
    for (std::size_t u = 1; u < c.tree.size(); ++u) {
        const Eigen::Vector3f p = c.tree.nodes[u].position;
        EXPECT_LT(lateral_offset(p), 0.006f) << "node " << u;
        EXPECT_NEAR(p.x(), 0.05f * static_cast<float>(u), 0.002f) << "node " << u << " slid along the branch";
    }
}

TEST(CylinderAxes, NodesPlacedByCircleFitsStay) {
    const auto points = lower_arc(0.03f, 0.5f * kPi, 1.0f, 150, 0.002f);
    Chain c(points, 1.0f, 0.05f, [&](float x) { return Eigen::Vector3f(x, 0.0f, -0.019f); });
    std::vector<bool> fixed(c.tree.size(), false);
    for (std::size_t u = 0; u < 8; ++u) fixed[u] = true;
    EXPECT_EQ(fit_cylinder_axes(c.tree, points, c.internode, on(), fixed), c.tree.size() - 8);
    for (std::size_t u = 0; u < c.tree.size(); ++u) {
        if (fixed[u])
            EXPECT_EQ(c.tree.nodes[u].position.z(), -0.019f) << "node " << u;
        else
            EXPECT_LT(lateral_offset(c.tree.nodes[u].position), 0.006f) << "node " << u;
    }
}

// A flat strip of points 4 cm wide fits a cylinder only over a sliver of its circumference (or
// not at all): no node moves.
TEST(CylinderAxes, FlatStripIsNotTrusted) {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> along(0.0f, 1.0f), across(-0.02f, 0.02f);
    std::normal_distribution<float> jitter(0.0f, 0.002f);
    std::vector<Eigen::Vector3f> points;
    // Coordinates drawn one statement each, last first: the order GCC evaluated the arguments in
    // (C++ leaves it open; Clang goes left to right), so both compilers make the same points.
    for (int i = 0; i < 300; ++i) {
        const float z = jitter(rng), y = across(rng), x = along(rng);
        points.emplace_back(x, y, z);
    }
    Chain c(points, 1.0f, 0.05f, [](float x) { return Eigen::Vector3f(x, 0.0f, 0.0f); });
    EXPECT_EQ(fit_cylinder_axes(c.tree, points, c.internode, on()), 0u);
    for (std::size_t u = 0; u < c.tree.size(); ++u)
        EXPECT_EQ(c.tree.nodes[u].position, Eigen::Vector3f(0.05f * static_cast<float>(u), 0, 0));
}

// A 5 mm twig bent along a 0.3 m circle: a wide cylinder fits the bend (its surface follows
// the twig), but the twig's cross-section is far narrower than that cylinder, so the spread
// test rejects it; with the spread test off the nodes would be dragged off the twig.
TEST(CylinderAxes, BentTwigIsNotTrusted) {
    std::mt19937 rng(4);
    std::vector<Eigen::Vector3f> points;
    const float bend = 0.3f;
    auto centre = [&](float x) { return Eigen::Vector3f(x, 0.0f, bend - std::sqrt(bend * bend - (x - 0.25f) * (x - 0.25f))); };
    std::uniform_real_distribution<float> along(0.0f, 0.5f), angle(-kPi, kPi);
    for (int i = 0; i < 400; ++i) {
        const float x = along(rng), a = angle(rng);
        points.push_back(centre(x) + 0.005f * Eigen::Vector3f(0.0f, std::cos(a), std::sin(a)));
    }
    auto max_offset = [&](const CylinderAxesOptions& o) {
        Chain c(points, 0.5f, 0.025f, centre);
        fit_cylinder_axes(c.tree, points, c.internode, o);
        float worst = 0;
        for (std::size_t u = 1; u < c.tree.size(); ++u)
            worst = std::max(worst, (c.tree.nodes[u].position - centre(0.025f * static_cast<float>(u))).norm());
        return worst;
    };
    CylinderAxesOptions o = on();
    o.window = 0.5f;
    o.min_arc = 0.0f;
    EXPECT_LT(max_offset(o), 0.002f);
    o.min_spread = 0.0f;
    EXPECT_GT(max_offset(o), 0.01f);
}

TEST(CylinderAxes, RejectsBadOptions) {
    TreeGraph tree;
    tree.add_node({0, 0, 0}, 0, -1);
    tree.add_node({1, 0, 0}, 0, 0);
    const std::vector<Eigen::Vector3f> points(3, Eigen::Vector3f::Zero());
    const std::vector<int> internode(3, 1);
    auto code = [&](auto change) {
        CylinderAxesOptions o = on();
        change(o);
        return test::error_code_of([&] { fit_cylinder_axes(tree, points, internode, o); });
    };
    EXPECT_EQ(code([](auto& o) { o.window = 0; }), ExitCode::Usage);
    EXPECT_EQ(code([](auto& o) { o.min_points = 5; }), ExitCode::Usage);
    EXPECT_EQ(code([](auto& o) { o.max_radius = o.min_radius; }), ExitCode::Usage);
    EXPECT_EQ(code([](auto& o) { o.max_rms = std::nanf(""); }), ExitCode::Usage);
    EXPECT_EQ(code([](auto& o) { o.min_spread = -1; }), ExitCode::Usage);
    EXPECT_EQ(code([](auto& o) { o.min_arc = 400; }), ExitCode::Usage);
    EXPECT_EQ(code([](auto& o) { o.max_tilt = -1; }), ExitCode::Usage);
    EXPECT_EQ(code([](auto& o) { o.max_shift = 0; }), ExitCode::Usage);
    const std::vector<int> short_internode(2, 1);
    EXPECT_EQ(test::error_code_of([&] { fit_cylinder_axes(tree, points, short_internode, on()); }), ExitCode::Internal);
}

TEST(CylinderAxes, CliSwitchReachesTheSummary) {
    test::TempDir dir;
    // The Y tree of synthetic_clouds.hpp, scanned from one side only.
    write_point_cloud(test::cloud_from(test::y_tree(), 3000.0f, 7, 0.45f), dir / "y.xyz");
    auto moved = [&](const std::string& flags) {
        const auto r = test::run_cli("reconstruct " + test::quoted(dir / "y.xyz") + " --out " + test::quoted(dir / "out") +
                                     " --overwrite " + flags);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        std::ifstream in(dir / "out" / "y_summary.json");
        std::stringstream text;
        text << in.rdbuf();
        const auto json = nlohmann::json::parse(text.str());
        EXPECT_EQ(json["options"]["cylinder_axes"].get<bool>(), flags.find("true") != std::string::npos);
        return json["tree"]["cylinder_axis_nodes"].get<int>();
    };
    EXPECT_EQ(moved(""), 0);  // off by default
    EXPECT_GT(moved("--cylinder-axes true"), 0);
    EXPECT_EQ(test::run_cli("reconstruct " + test::quoted(dir / "y.xyz") + " --out " + test::quoted(dir / "out") + " --cylinder-window 0")
                      .exit_code,
              1);
}
