// Parser of L-system files and module strings: syntax accepted, expressions, and one-line errors
// with line and column.
#include "core/error.hpp"
#include "lsystem/lsystem.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace treelobes;
using namespace treelobes::lsystem;

namespace {

// Message of the Error thrown by parsing `text`, or "" when it parses.
std::string parse_error(const std::string& text, const ParseOptions& options = {}) {
    try {
        parse_lsystem(text, "test.lsys", options);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// Value of a constant expression, evaluated through an axiom parameter.
double value_of(const std::string& expression, const std::string& defines = "") {
    const LSystem s = parse_lsystem(defines + "axiom: A(" + expression + ")\n");
    return s.axiom.params(0)[0];
}

}  // namespace

TEST(ModuleStringParse, NamesParametersAndBrackets) {
    const ModuleString s = parse_module_string("C1[C2[C3][C4]][C5] F(1.5)+(30)A(2, -0.5e1)$");
    ASSERT_EQ(s.size(), 17u);
    EXPECT_EQ(s.name(0), "C1");
    EXPECT_EQ(s.name(1), "[");
    EXPECT_EQ(s.symbol(1), Alphabet::kPush);
    EXPECT_EQ(s.name(13), "F");
    EXPECT_EQ(s.params(13)[0], 1.5);
    EXPECT_EQ(s.name(14), "+");
    EXPECT_EQ(s.name(15), "A");
    ASSERT_EQ(s.param_count(15), 2u);
    EXPECT_EQ(s.params(15)[1], -5.0);
    EXPECT_EQ(s.name(16), "$");
    EXPECT_EQ(s.to_string(), "C1[C2[C3][C4]][C5]F(1.5)+(30)A(2,-5)$");
}

TEST(ModuleStringParse, LettersAreSeparateModulesUnlessDeclared) {
    EXPECT_EQ(parse_module_string("FF[+F]").size(), 6u);  // ABOP: one letter per module
    auto alphabet = std::make_shared<Alphabet>();
    alphabet->declare_long_name("Apex");
    const ModuleString s = parse_module_string("Apex(1)AF", "<string>", alphabet);
    ASSERT_EQ(s.size(), 3u);
    EXPECT_EQ(s.name(0), "Apex");
    EXPECT_EQ(s.name(1), "A");
}

TEST(ModuleStringParse, ErrorsGiveLineAndColumn) {
    try {
        parse_module_string("F(1)\nF(2", "in.txt");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), "in.txt: line 2, column 4: expected ',' or ')' after a parameter of 'F'");
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
    }
    EXPECT_NE(std::string(parse_error("axiom: F(1)#x\n")), "x");  // '#' starts a comment: fine
    try {
        parse_module_string("F(1)<A", "in.txt");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), "in.txt: line 1, column 5: expected a module name but found '<'");
    }
}

TEST(Expressions, PrecedenceAndFunctions) {
    EXPECT_EQ(value_of("1+2*3"), 7);
    EXPECT_EQ(value_of("(1+2)*3"), 9);
    EXPECT_EQ(value_of("-2^2"), -4);    // power binds tighter than unary minus
    EXPECT_EQ(value_of("2^3^2"), 512);  // right-associative
    EXPECT_EQ(value_of("2^-1"), 0.5);
    EXPECT_EQ(value_of("7 % 4"), 3);
    EXPECT_EQ(value_of("10/4"), 2.5);
    EXPECT_EQ(value_of("3 > 2 && 1 <= 1"), 1);
    EXPECT_EQ(value_of("3 = 2 or not 0"), 1);
    EXPECT_EQ(value_of("1 != 1 || 2 == 3"), 0);
    EXPECT_EQ(value_of("sqrt(16) + min(2, 5) * max(1, 3)"), 10);
    EXPECT_NEAR(value_of("atan2(1, 1) * 4"), 3.14159265358979, 1e-12);
    EXPECT_NEAR(value_of("cos(pi)"), -1.0, 1e-15);
    EXPECT_EQ(value_of("floor(2.7) + ceil(0.2) + abs(-3) + sign(-9) + round(2.5)"), 8);
    EXPECT_EQ(value_of(".5 + 1e-1 * 10"), 1.5);
    EXPECT_EQ(value_of("b * 2", "#define a 3\n#define b a + 1\n"), 8);
}

TEST(LSystemParse, HeadersRulesAndComments) {
    const LSystem s = parse_lsystem(R"(/* a block
       comment over lines */
#define r 0.5   # trailing comment
Lsystem: 1
derivation length: 2*2
seed: 18446744073709551615
angle: 30
step: 2
width: 0.1
width factor: 0.5
tropism: 0, 1 - 1, -1
elasticity: 0.25
#ignore: + -
axiom: A(1) B
A(l) : l > r -> F(l)[+A(l*r)]A(l*r)
A(l) : * --> L(l) : 0.5
A(l) → L(2*l) : 1.5
B -> *
homomorphism:
L(s) -> F(s)
endlsystem
this line is after endlsystem and ignored
)");
    EXPECT_EQ(s.derivation_length, 4);
    EXPECT_EQ(s.seed, 18446744073709551615ull);
    EXPECT_EQ(s.turtle.angle_deg, 30);
    EXPECT_EQ(s.turtle.step, 2);
    EXPECT_EQ(s.turtle.initial_width, 0.1);
    EXPECT_EQ(s.turtle.width_factor, 0.5);
    EXPECT_EQ(s.turtle.tropism, Eigen::Vector3d(0, 0, -1));
    EXPECT_EQ(s.turtle.elasticity, 0.25);
    EXPECT_EQ(s.ignored.size(), 2u);
    EXPECT_EQ(s.axiom.to_string(), "A(1)B");
    ASSERT_EQ(s.productions.size(), 4u);
    EXPECT_TRUE(s.productions[0].condition.has_value());
    EXPECT_EQ(s.productions[0].successor.size(), 6u);      // F [ + A ] A
    EXPECT_FALSE(s.productions[1].condition.has_value());  // `*`
    EXPECT_EQ(s.productions[1].probability, 0.5);
    EXPECT_EQ(s.productions[2].probability, 1.5);
    EXPECT_TRUE(s.productions[3].successor.empty());  // cpfg's empty successor
    EXPECT_EQ(s.productions[0].line, 15);
    ASSERT_EQ(s.homomorphism.size(), 1u);
    EXPECT_EQ(s.constants.at("r"), 0.5);
}

TEST(LSystemParse, ContextsAndDefineOverrides) {
    ParseOptions options;
    options.defines["k"] = 7;
    const LSystem s = parse_lsystem("#define k 2\naxiom: A\nB(x) C < A(y) > D(z) : x + y + z > k -> E(x, y, z)\n", "t", options);
    ASSERT_EQ(s.productions.size(), 1u);
    const Rule& r = s.productions[0];
    EXPECT_EQ(r.left_context.size(), 2u);
    EXPECT_EQ(r.right_context.size(), 1u);
    EXPECT_EQ(r.bound_params, 3u);
    EXPECT_EQ(s.constants.at("k"), 7);
    options.defines["typo"] = 1;
    try {
        parse_lsystem("#define k 2\naxiom: A\n", "t", options);
        FAIL() << "override of an unknown constant accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::Usage);
        EXPECT_NE(std::string(e.what()).find("--define typo"), std::string::npos);
    }
}

TEST(LSystemParse, ErrorsNameLineAndColumn) {
    // Each message is one line with the file, the line, the column and what was expected.
    EXPECT_EQ(parse_error("axiom: A(1)\nA(l) -> B(x)\n"),
              "test.lsys: line 2, column 11: unknown name 'x' (not a parameter of the predecessor, a #define constant, step, "
              "steps or pi)");
    EXPECT_EQ(parse_error("axiom: A\nA B\n"),
              "test.lsys: line 2, column 1: expected a rule 'predecessor -> successor', a header such as 'axiom:' or a #define");
    EXPECT_EQ(parse_error("axiom: A\n  A(l+1) -> B\n"), "test.lsys: line 2, column 6: expected ',' or ')' after a parameter of A");
    EXPECT_EQ(parse_error("axiom: A\nA B -> C\n"),
              "test.lsys: line 2, column 1: the predecessor must be one module; write contexts as 'left < A > right'");
    EXPECT_EQ(parse_error("axiom: A\nA -> B : 0\n"), "test.lsys: line 2, column 10: a rule probability must be greater than 0");
    EXPECT_EQ(parse_error("axiom: A\nA -> B(foo(1))\n"), "test.lsys: line 2, column 8: unknown function 'foo'");
    EXPECT_EQ(parse_error("axiom: A\nA -> B(sqrt(1, 2))\n"), "test.lsys: line 2, column 8: sqrt() takes 1 argument, got 2");
    EXPECT_EQ(parse_error("derivation length: 2.5\naxiom: A\n"),
              "test.lsys: line 1, column 20: derivation length must be a whole number from 0 to 100000");
    EXPECT_EQ(parse_error("#define a 1\n#define a 2\naxiom: A\n"), "test.lsys: line 2, column 9: constant 'a' is defined twice");
    EXPECT_EQ(parse_error("#define step 1\naxiom: A\n"), "test.lsys: line 1, column 9: 'step' is a built-in name and cannot be #defined");
    EXPECT_EQ(parse_error("axiom: A\n/* open\n"), "test.lsys: line 2: '/*' comment is never closed");
    EXPECT_EQ(parse_error("derivation length: 3\n"), "test.lsys: no 'axiom:' line");
    EXPECT_EQ(parse_error("axiom: A(1/0)\n"), "test.lsys: line 1, column 10: parameter is not a finite number (division by zero?)");
    EXPECT_EQ(parse_error("axiom: A\nA(x, x) -> B\n"), "test.lsys: line 2, column 1: parameter name 'x' is used twice in the predecessor");
    EXPECT_EQ(parse_error("axiom: A\nA -> B(ran(1))\nA : ran(1) -> B\nB -> C : ran(1)\n"),
              "test.lsys: line 4, column 10: random function 'ran' is not allowed here (only in rules)");
    EXPECT_EQ(parse_error("tropism: 0 0 -1\naxiom: A\n"),
              "test.lsys: line 1, column 12: tropism needs three components separated by commas: x, y, z");
    EXPECT_EQ(parse_error("axiom: A\nA -> [B\n"), "");  // unbalanced successors are legal until interpretation
    EXPECT_EQ(parse_error("axiom: A\nA < [B] -> C\n"),
              "test.lsys: line 2, column 5: brackets are not supported in predecessors or contexts");
    EXPECT_EQ(parse_error("axiom: A\nA -> B(" + std::string(200, '(') + "\n"),
              "test.lsys: line 2, column 40: expression nested too deeply");
    EXPECT_EQ(parse_error("axiom: A(" + std::string(100, '(') + "1" + std::string(100, ')') + ")\n"),
              "test.lsys: line 1, column 42: expression nested too deeply");
}
