#include "lsystem/expression.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <unordered_map>

namespace treelobes::lsystem::detail {

namespace {

struct FunctionInfo {
    Op op;
    int arity;
    bool random;
};

const std::unordered_map<std::string, FunctionInfo>& functions() {
    static const std::unordered_map<std::string, FunctionInfo> table = {
            {"sin", {Op::Sin, 1, false}},     {"cos", {Op::Cos, 1, false}},        {"tan", {Op::Tan, 1, false}},
            {"asin", {Op::Asin, 1, false}},   {"acos", {Op::Acos, 1, false}},      {"atan", {Op::Atan, 1, false}},
            {"sqrt", {Op::Sqrt, 1, false}},   {"exp", {Op::Exp, 1, false}},        {"log", {Op::Log, 1, false}},
            {"abs", {Op::Abs, 1, false}},     {"floor", {Op::Floor, 1, false}},    {"ceil", {Op::Ceil, 1, false}},
            {"round", {Op::Round, 1, false}}, {"sign", {Op::Sign, 1, false}},      {"atan2", {Op::Atan2, 2, false}},
            {"min", {Op::Min, 2, false}},     {"max", {Op::Max, 2, false}},        {"pow", {Op::PowFn, 2, false}},
            {"ran", {Op::Ran, 1, true}},      {"uniform", {Op::Uniform, 2, true}}, {"normal", {Op::Normal, 2, true}},
    };
    return table;
}

// Stack effect of one instruction: how many values it pops and pushes.
int pops(Op op) {
    switch (op) {
        case Op::Const:
        case Op::Param:
        case Op::Step:
        case Op::Steps:
            return 0;
        case Op::Neg:
        case Op::Not:
        case Op::Sin:
        case Op::Cos:
        case Op::Tan:
        case Op::Asin:
        case Op::Acos:
        case Op::Atan:
        case Op::Sqrt:
        case Op::Exp:
        case Op::Log:
        case Op::Abs:
        case Op::Floor:
        case Op::Ceil:
        case Op::Round:
        case Op::Sign:
        case Op::Ran:
            return 1;
        default:
            return 2;
    }
}

}  // namespace

class ExpressionParser {
public:
    ExpressionParser(Cursor& cursor, const NameScope& scope) : c_(cursor), scope_(scope) {}

    Expression parse() {
        parse_or();
        finish();
        return std::move(expr_);
    }

private:
    static constexpr int kMaxNesting = 64;  // guards the recursion against "((((...": one clear error

    void emit(Op op, int slot = 0, double value = 0.0) { expr_.code_.push_back({op, slot, value}); }

    bool consume_word(std::string_view word) {
        c_.skip_space();
        const std::string_view rest = c_.rest();
        if (rest.substr(0, word.size()) != word) return false;
        if (rest.size() > word.size() && is_identifier_char(rest[word.size()])) return false;
        c_.set_pos(c_.pos() + word.size());
        return true;
    }
    bool consume_op(std::string_view op) {
        c_.skip_space();
        return c_.consume(op);
    }

    void parse_or() {
        parse_and();
        while (consume_op("||") || consume_word("or")) {
            parse_and();
            emit(Op::Or);
        }
    }
    void parse_and() {
        parse_equality();
        while (consume_op("&&") || consume_word("and")) {
            parse_equality();
            emit(Op::And);
        }
    }
    void parse_equality() {
        parse_relational();
        for (;;) {
            if (consume_op("==")) {
                parse_relational();
                emit(Op::Eq);
            } else if (consume_op("!=")) {
                parse_relational();
                emit(Op::Ne);
            } else if (c_.peek() == '=') {
                c_.get();
                parse_relational();
                emit(Op::Eq);
            } else
                return;
        }
    }
    void parse_relational() {
        parse_additive();
        for (;;) {
            if (consume_op("<=")) {
                parse_additive();
                emit(Op::Le);
            } else if (consume_op(">=")) {
                parse_additive();
                emit(Op::Ge);
            } else if (consume_op("<")) {
                parse_additive();
                emit(Op::Lt);
            } else if (consume_op(">")) {
                // "->" never follows an operand inside an expression; leave it for the rule parser.
                parse_additive();
                emit(Op::Gt);
            } else
                return;
        }
    }
    void parse_additive() {
        parse_multiplicative();
        for (;;) {
            c_.skip_space();
            // A '-' followed by '>' is the rule arrow, not a subtraction.
            if (c_.peek() == '-' && c_.peek(1) == '>') return;
            if (c_.peek() == '-' && c_.peek(1) == '-' && c_.peek(2) == '>') return;
            if (c_.consume('+')) {
                parse_multiplicative();
                emit(Op::Add);
            } else if (c_.consume('-')) {
                parse_multiplicative();
                emit(Op::Sub);
            } else
                return;
        }
    }
    void parse_multiplicative() {
        parse_unary();
        for (;;) {
            c_.skip_space();
            if (c_.consume('*')) {
                parse_unary();
                emit(Op::Mul);
            } else if (c_.consume('/')) {
                parse_unary();
                emit(Op::Div);
            } else if (c_.consume('%')) {
                parse_unary();
                emit(Op::Mod);
            } else
                return;
        }
    }
    void parse_unary() {
        Nesting guard(*this);
        c_.skip_space();
        if (c_.peek() == '-' && c_.peek(1) != '>') {
            c_.get();
            parse_unary();
            emit(Op::Neg);
            return;
        }
        if (c_.consume('+')) {
            parse_unary();
            return;
        }
        if (c_.peek() == '!' && c_.peek(1) != '=') {
            c_.get();
            parse_unary();
            emit(Op::Not);
            return;
        }
        if (consume_word("not")) {
            parse_unary();
            emit(Op::Not);
            return;
        }
        parse_power();
    }
    void parse_power() {
        parse_primary();
        c_.skip_space();
        if (c_.consume('^')) {
            parse_unary();  // right-associative; allows 2^-1
            emit(Op::Pow);
        }
    }
    void parse_primary() {
        Nesting guard(*this);
        c_.skip_space();
        const char next = c_.peek();
        if (c_.consume('(')) {
            parse_or();
            c_.skip_space();
            if (!c_.consume(')')) c_.fail("expected ')' but found " + c_.describe_next());
            return;
        }
        if (std::isdigit(static_cast<unsigned char>(next)) || (next == '.' && std::isdigit(static_cast<unsigned char>(c_.peek(1))))) {
            parse_number();
            return;
        }
        if (is_identifier_start(next)) {
            parse_name();
            return;
        }
        c_.fail("expected a number, a name or '(' but found " + c_.describe_next());
    }
    void parse_number() {
        const std::string_view rest = c_.rest();
        double value = 0;
        const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), value);
        if (ec != std::errc() || !std::isfinite(value)) c_.fail("malformed or out-of-range number");
        c_.set_pos(c_.pos() + static_cast<std::size_t>(end - rest.data()));
        emit(Op::Const, 0, value);
    }
    void parse_name() {
        const std::size_t start = c_.pos();
        while (is_identifier_char(c_.peek())) c_.get();
        const std::string name(c_.text().substr(start, c_.pos() - start));
        c_.skip_space();
        if (c_.peek() == '(') {
            parse_call(name, start);
            return;
        }
        if (scope_.formals) {
            for (std::size_t k = 0; k < scope_.formals->size(); ++k)
                if ((*scope_.formals)[k] == name) {
                    emit(Op::Param, static_cast<int>(k));
                    return;
                }
        }
        if (scope_.constants) {
            const auto it = scope_.constants->find(name);
            if (it != scope_.constants->end()) {
                emit(Op::Const, 0, it->second);
                return;
            }
        }
        if (name == "pi") {
            emit(Op::Const, 0, 3.14159265358979323846);
            return;
        }
        if (scope_.allow_step && name == "step") {
            emit(Op::Step);
            return;
        }
        if (scope_.allow_step && name == "steps") {
            emit(Op::Steps);
            return;
        }
        c_.fail_at(start, "unknown name '" + name + "' (not a parameter of the predecessor, a #define constant" +
                                  std::string(scope_.allow_step ? ", step, steps" : "") + " or pi)");
    }
    void parse_call(const std::string& name, std::size_t start) {
        const auto it = functions().find(name);
        if (it == functions().end()) c_.fail_at(start, "unknown function '" + name + "'");
        const FunctionInfo info = it->second;
        if (info.random && !scope_.allow_random) c_.fail_at(start, "random function '" + name + "' is not allowed here (only in rules)");
        c_.consume('(');
        int args = 0;
        c_.skip_space();
        if (!c_.consume(')')) {
            for (;;) {
                parse_or();
                ++args;
                c_.skip_space();
                if (c_.consume(')')) break;
                if (!c_.consume(',')) c_.fail("expected ',' or ')' in the arguments of " + name + "()");
            }
        }
        if (args != info.arity)
            c_.fail_at(start, name + "() takes " + std::to_string(info.arity) + " argument" + (info.arity == 1 ? "" : "s") + ", got " +
                                      std::to_string(args));
        if (info.random) expr_.uses_random_ = true;
        emit(info.op);
    }

    // Computes the stack depth and folds an expression without parameters, step or random into
    // one constant (so `l*r1` with #define r1 costs one multiply at derivation time).
    void finish() {
        int depth = 0, max_depth = 0;
        bool variable = expr_.uses_random_;
        for (const auto& ins : expr_.code_) {
            depth += 1 - pops(ins.op);
            max_depth = std::max(max_depth, depth);
            if (ins.op == Op::Param || ins.op == Op::Step || ins.op == Op::Steps) variable = true;
        }
        expr_.max_stack_ = std::max(1, max_depth);
        if (!variable) {
            const double value = expr_.evaluate({});
            expr_.code_.assign(1, {Op::Const, 0, value});
            expr_.max_stack_ = 1;
        }
    }

    struct Nesting {
        explicit Nesting(ExpressionParser& p) : parser(p) {
            if (++parser.nesting_ > kMaxNesting) parser.c_.fail("expression nested too deeply");
        }
        ~Nesting() { --parser.nesting_; }
        ExpressionParser& parser;
    };

    Cursor& c_;
    const NameScope& scope_;
    Expression expr_;
    int nesting_ = 0;
};

Expression parse_expression(Cursor& cursor, const NameScope& scope) { return ExpressionParser(cursor, scope).parse(); }

double parse_constant_expression(Cursor& cursor, const std::unordered_map<std::string, double>& constants) {
    NameScope scope;
    scope.constants = &constants;
    const std::size_t start = cursor.pos();
    const Expression e = parse_expression(cursor, scope);
    const double value = e.constant_value();
    if (!std::isfinite(value)) cursor.fail_at(start, "expression is not a finite number (division by zero?)");
    return value;
}

double Expression::evaluate(const EvalContext& context) const {
    // Expressions are short; a fixed stack covers all but pathological ones.
    if (code_.empty()) return 0.0;
    std::array<double, 64> small;
    small[0] = 0.0;  // (the program always writes it; this keeps -Wmaybe-uninitialized quiet)
    std::vector<double> large;
    double* stack = small.data();
    if (max_stack_ > static_cast<int>(small.size())) {
        large.resize(static_cast<std::size_t>(max_stack_));
        stack = large.data();
    }
    int top = -1;
    auto random = [&]() -> Rng& {
        static thread_local Rng fallback(0);  // only for constant folding, which has no random calls
        return context.random ? *context.random : fallback;
    };
    for (const Instruction& ins : code_) {
        switch (ins.op) {
            case Op::Const:
                stack[++top] = ins.value;
                break;
            case Op::Param:
                stack[++top] = context.params[static_cast<std::size_t>(ins.slot)];
                break;
            case Op::Step:
                stack[++top] = context.step;
                break;
            case Op::Steps:
                stack[++top] = context.steps;
                break;
            case Op::Neg:
                stack[top] = -stack[top];
                break;
            case Op::Not:
                stack[top] = stack[top] == 0.0 ? 1.0 : 0.0;
                break;
            case Op::Sin:
                stack[top] = std::sin(stack[top]);
                break;
            case Op::Cos:
                stack[top] = std::cos(stack[top]);
                break;
            case Op::Tan:
                stack[top] = std::tan(stack[top]);
                break;
            case Op::Asin:
                stack[top] = std::asin(stack[top]);
                break;
            case Op::Acos:
                stack[top] = std::acos(stack[top]);
                break;
            case Op::Atan:
                stack[top] = std::atan(stack[top]);
                break;
            case Op::Sqrt:
                stack[top] = std::sqrt(stack[top]);
                break;
            case Op::Exp:
                stack[top] = std::exp(stack[top]);
                break;
            case Op::Log:
                stack[top] = std::log(stack[top]);
                break;
            case Op::Abs:
                stack[top] = std::fabs(stack[top]);
                break;
            case Op::Floor:
                stack[top] = std::floor(stack[top]);
                break;
            case Op::Ceil:
                stack[top] = std::ceil(stack[top]);
                break;
            case Op::Round:
                stack[top] = std::round(stack[top]);
                break;
            case Op::Sign:
                stack[top] = static_cast<double>((stack[top] > 0) - (stack[top] < 0));
                break;
            case Op::Ran:
                stack[top] = stack[top] * random().uniform();
                break;
            default: {
                const double b = stack[top--];
                double& a = stack[top];
                switch (ins.op) {
                    case Op::Add:
                        a += b;
                        break;
                    case Op::Sub:
                        a -= b;
                        break;
                    case Op::Mul:
                        a *= b;
                        break;
                    case Op::Div:
                        a /= b;
                        break;
                    case Op::Mod:
                        a = std::fmod(a, b);
                        break;
                    case Op::Pow:
                    case Op::PowFn:
                        a = std::pow(a, b);
                        break;
                    case Op::Lt:
                        a = a < b;
                        break;
                    case Op::Le:
                        a = a <= b;
                        break;
                    case Op::Gt:
                        a = a > b;
                        break;
                    case Op::Ge:
                        a = a >= b;
                        break;
                    case Op::Eq:
                        a = a == b;
                        break;
                    case Op::Ne:
                        a = a != b;
                        break;
                    case Op::And:
                        a = (a != 0.0 && b != 0.0);
                        break;
                    case Op::Or:
                        a = (a != 0.0 || b != 0.0);
                        break;
                    case Op::Atan2:
                        a = std::atan2(a, b);
                        break;
                    case Op::Min:
                        a = std::min(a, b);
                        break;
                    case Op::Max:
                        a = std::max(a, b);
                        break;
                    case Op::Uniform:
                        a = random().uniform(a, b);
                        break;
                    case Op::Normal:
                        a = random().normal(a, b);
                        break;
                    default:
                        break;
                }
            }
        }
    }
    return stack[0];
}

}  // namespace treelobes::lsystem::detail
