// Turtle interpretation: the commands, main-child-first order, widths, tropism, leaves, and the
// trunk heights of the classic models.
#include "core/error.hpp"
#include "lsystem/lsystem.hpp"
#include "lsystem_test_util.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>

using namespace treelobes;
using namespace treelobes::lsystem;
using namespace treelobes::lsystem::test_util;

namespace {

TurtleResult draw(const std::string& text, const TurtleOptions& options = {}) { return interpret(parse_module_string(text), options); }

void expect_near(const Eigen::Vector3f& a, const Eigen::Vector3d& b, double tolerance = 1e-6) {
    EXPECT_NEAR(a.x(), b.x(), tolerance);
    EXPECT_NEAR(a.y(), b.y(), tolerance);
    EXPECT_NEAR(a.z(), b.z(), tolerance);
}

}  // namespace

// Lluch et al. 2010, via Ong's seminar report, §2.2: F(1) [ R(90) F(1) ] F(2), with + as the rotation.
TEST(Turtle, Seed003BracketExample) {
    const TurtleResult r = draw("F(1)[+(90)F(1)]F(2)");
    ASSERT_EQ(r.tree.size(), 4u);
    r.tree.validate("turtle");
    expect_near(r.tree.nodes[0].position, {0, 0, 0});
    expect_near(r.tree.nodes[1].position, {0, 0, 1});
    expect_near(r.tree.nodes[2].position, {0, 1, 1});  // + turns H toward L = +y
    expect_near(r.tree.nodes[3].position, {0, 0, 3});  // the state was restored by ']'
    // Main child first: the continuation F(2) (drawn last) before the lateral.
    EXPECT_EQ(r.tree.nodes[1].children, (std::vector<int>{3, 2}));
    EXPECT_EQ(r.depth, (std::vector<int>{0, 0, 1, 0}));
    EXPECT_EQ(r.tree.branch_orders(), (std::vector<int>{0, 0, 1, 0}));
}

TEST(Turtle, RotationCommands) {
    // Frame: H = +z, L = +y, U = -x.
    expect_near(draw("&(90)F").tree.nodes[1].position, {1, 0, 0});         // pitch down: toward -U
    expect_near(draw("^(90)F").tree.nodes[1].position, {-1, 0, 0});        // pitch up: toward U
    expect_near(draw("-(90)F").tree.nodes[1].position, {0, -1, 0});        // turn right
    expect_near(draw("|F").tree.nodes[1].position, {0, 0, -1});            // turn around
    expect_near(draw("\\(90)+(90)F").tree.nodes[1].position, {-1, 0, 0});  // roll moves L to U
    expect_near(draw("/(90)+(90)F").tree.nodes[1].position, {1, 0, 0});
    // Default angle and step from the options.
    TurtleOptions options;
    options.angle_deg = 90;
    options.step = 2;
    expect_near(draw("+F", options).tree.nodes[1].position, {0, 2, 0});
}

TEST(Turtle, RollHorizontalMakesLeftHorizontal) {
    const ModuleString s = parse_module_string("&(30)/(40)$", "<string>", nullptr);
    Turtle t(s.alphabet(), {});
    t.apply(s, 0, 2);
    const Eigen::Vector3d heading = t.state().heading;
    EXPECT_GT(std::fabs(t.state().left.z()), 0.1);  // rolled: L not horizontal
    t.apply(s, 2);
    EXPECT_NEAR(t.state().left.z(), 0.0, 1e-12);
    EXPECT_TRUE(t.state().heading.isApprox(heading));
    EXPECT_NEAR(t.state().heading.cross(t.state().left).dot(t.state().up), 1.0, 1e-12);
}

TEST(Turtle, WidthsBecomeRadii) {
    const TurtleResult r = draw("!(0.2)F(1)!(0.1)F(1)!F(1)");
    EXPECT_FLOAT_EQ(r.tree.nodes[0].radius, 0.1f);  // the root takes its first internode's width
    EXPECT_FLOAT_EQ(r.tree.nodes[1].radius, 0.1f);
    EXPECT_FLOAT_EQ(r.tree.nodes[2].radius, 0.05f);
    EXPECT_FLOAT_EQ(r.tree.nodes[3].radius, 0.035f);  // '!' alone: width * 0.7
    TurtleOptions options;
    options.root_width = 0.5;
    EXPECT_FLOAT_EQ(draw("!(0.2)F(1)", options).tree.nodes[0].radius, 0.25f);
    EXPECT_THROW(draw("!(-1)F"), Error);
}

TEST(Turtle, MoveWithoutDrawingKeepsTheTreeConnected) {
    const TurtleResult r = draw("F(1)f(2)F(1)");
    ASSERT_EQ(r.tree.size(), 4u);
    expect_near(r.tree.nodes[3].position, {0, 0, 4});
    EXPECT_EQ(r.drawn, (std::vector<unsigned char>{0, 1, 0, 1}));
    EXPECT_EQ(r.tree.nodes[2].radius, 0.0f);
}

TEST(Turtle, LeavesAreRecordedWithTheirNode) {
    const TurtleResult r = draw("F(1)[+(90)L(0.3)]F(1)L");
    ASSERT_EQ(r.leaves.size(), 2u);
    EXPECT_EQ(r.leaves[0].node, 1);
    EXPECT_FLOAT_EQ(r.leaves[0].size, 0.3f);
    expect_near(r.leaves[0].heading, {0, 1, 0});
    EXPECT_EQ(r.leaves[0].module, 3u);  // F [ + L
    EXPECT_EQ(r.leaves[1].node, 2);
    EXPECT_FLOAT_EQ(r.leaves[1].size, 1.0f);
    expect_near(r.leaves[1].position, {0, 0, 2});
}

TEST(Turtle, SetHeadSetsAnAbsoluteDirection) {
    const TurtleResult r = draw("SetHead(3,0,4)F(5)SetHead(0,0,-2)F(1)");
    expect_near(r.tree.nodes[1].position, {3, 0, 4});
    expect_near(r.tree.nodes[2].position, {3, 0, 3});
    EXPECT_THROW(draw("SetHead(0,0,0)F"), Error);
}

// ABOP eq. 2.4: after F the heading turns about H x T by e * |H x T|.
TEST(Turtle, TropismBendsTowardT) {
    TurtleOptions options;
    options.elasticity = 0.5;
    options.tropism = {0, 0, -1};
    const TurtleResult r = draw("&(90)F(1)F(1)", options);
    expect_near(r.tree.nodes[1].position, {1, 0, 0});
    expect_near(r.tree.nodes[2].position, {1 + std::cos(0.5), 0, -std::sin(0.5)});
    // Parallel to T: no bending.
    const TurtleResult up = draw("F(1)F(1)", options);
    expect_near(up.tree.nodes[2].position, {0, 0, 2});
}

TEST(Turtle, UnbalancedBracketsAreErrors) {
    EXPECT_THROW(draw("F]F"), Error);
    EXPECT_THROW(draw("F[F"), Error);
}

// Honda's trunk (A) keeps its direction: height 1 + r1 + ... + r1^(n-1), on the z axis.
TEST(Turtle, HondaTrunkHeight) {
    const LSystem s = load_lsystem(example("honda_monopodial.lsys"));
    for (int n : {1, 5, 10}) {
        DeriveOptions options;
        options.steps = n;
        const TurtleResult r = interpret(apply_homomorphism(s, derive(s, options)), s.turtle);
        r.tree.validate("honda");
        EXPECT_EQ(r.tree.size(), std::size_t{1} << n);  // root + 2^n - 1 internodes
        const double height = (1.0 - std::pow(0.9, n)) / (1.0 - 0.9);
        expect_near(trunk_top(r), {0, 0, height}, 1e-5);
        EXPECT_FLOAT_EQ(r.tree.nodes[0].radius, 0.075f);  // w0 / 2
    }
}

// Ternary tree: the trunk is parallel to T so it stays straight: 200*lr^n + 50*lr^(n-1) units.
TEST(Turtle, TernaryTrunkHeightAndTropism) {
    LSystem s = load_lsystem(example("abop_ternary_tropism.lsys"));
    const TurtleResult r = interpret(derive(s), s.turtle);
    r.tree.validate("ternary");
    EXPECT_EQ(r.tree.size(), 1458u);
    const double height = 0.01 * (200 * std::pow(1.109, 6) + 50 * std::pow(1.109, 5));
    expect_near(trunk_top(r), {0, 0, height}, 1e-5);
    // Tropism pulls the branches down: without it the nodes are 2 m higher on average (9.96 m
    // against 7.91 m; the highest, near-vertical shoots barely bend).
    s.turtle.elasticity = 0;
    const TurtleResult straight = interpret(derive(s), s.turtle);
    auto mean_height = [](const TurtleResult& t) {
        double z = 0;
        for (const auto& n : t.tree.nodes) z += n.position.z();
        return z / static_cast<double>(t.tree.size());
    };
    EXPECT_LT(mean_height(r), mean_height(straight) - 1.5);
    expect_near(trunk_top(straight), {0, 0, height}, 1e-5);
}
