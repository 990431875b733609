// Arithmetic expressions of parametric L-systems: parameters of successor modules, conditions,
// probabilities and #define values. Compiled once at parse time into a small stack program
// (constant sub-expressions folded), evaluated for every rewritten module.
//
// Syntax (C-like, as in cpfg; `and or not` as in L-Py):
//   numbers 1  0.5  .5  2e-3 · names (rule parameters, #define constants, `step`, `steps`, `pi`)
//   unary - + !/not · ^ (power, right-assoc., binds tighter than unary minus: -2^2 = -4)
//   * / % · + - · < <= > >= · == != (and = as equality, the notation of Lluch et al. 2010) · &&/and · ||/or
//   functions: sin cos tan asin acos atan (radians), atan2(y,x), sqrt exp log abs floor ceil
//   round sign min(a,b) max(a,b) pow(a,b) · random: ran(x) in [0,x), uniform(a,b), normal(m,s)
// Comparisons and logic give 1 or 0; a condition holds when it is non-zero.
#pragma once

#include "core/random.hpp"
#include "lsystem/text_cursor.hpp"

#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace treelobes::lsystem::detail {

enum class Op : unsigned char {
    Const,
    Param,
    Step,
    Steps,
    Neg,
    Not,
    Add,
    Sub,
    Mul,
    Div,
    Mod,
    Pow,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sqrt,
    Exp,
    Log,
    Abs,
    Floor,
    Ceil,
    Round,
    Sign,
    Atan2,
    Min,
    Max,
    PowFn,
    Ran,
    Uniform,
    Normal,
};

struct Instruction {
    Op op = Op::Const;
    int slot = 0;        // Param: index into the bound parameters
    double value = 0.0;  // Const
};

// What names an expression may use.
struct NameScope {
    const std::vector<std::string>* formals = nullptr;                   // rule parameters -> slots
    const std::unordered_map<std::string, double>* constants = nullptr;  // #define values
    bool allow_step = false;                                             // `step` (1-based number of the step being applied), `steps`
    bool allow_random = false;                                           // ran(), uniform(), normal()
};

struct EvalContext {
    std::span<const double> params;
    double step = 0;
    double steps = 0;
    Rng* random = nullptr;
};

class Expression {
public:
    Expression() = default;
    explicit Expression(double constant) { code_.push_back({Op::Const, 0, constant}); }

    double evaluate(const EvalContext& context) const;
    bool is_constant() const { return code_.size() == 1 && code_[0].op == Op::Const; }
    double constant_value() const { return code_[0].value; }
    bool uses_random() const { return uses_random_; }

private:
    friend class ExpressionParser;
    std::vector<Instruction> code_;
    int max_stack_ = 1;
    bool uses_random_ = false;
};

// Parses one expression at the cursor and stops before the first character that cannot continue
// it (`,` `)` `:` ...). Throws Error::input with line and column.
Expression parse_expression(Cursor& cursor, const NameScope& scope);

// Parses and evaluates an expression that may only use constants (headers, #define, probabilities).
double parse_constant_expression(Cursor& cursor, const std::unordered_map<std::string, double>& constants);

}  // namespace treelobes::lsystem::detail
