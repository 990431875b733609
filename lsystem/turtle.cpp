#include "lsystem/turtle.hpp"

#include "core/angles.hpp"
#include "core/error.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace treelobes::lsystem {

namespace {

std::string module_text(const ModuleString& string, std::size_t i) {
    return "'" + string.to_string(i, i + 1) + "' (module " + std::to_string(i) + ")";
}

}  // namespace

void check_brackets(const ModuleString& string, const std::string& source_name) {
    const std::string source = source_name.empty() ? "module string" : source_name;
    std::vector<std::size_t> open;
    for (std::size_t i = 0; i < string.size(); ++i) {
        if (string.symbol(i) == Alphabet::kPush) open.push_back(i);
        if (string.symbol(i) == Alphabet::kPop) {
            if (open.empty()) throw Error::input(source, "']' at module " + std::to_string(i) + " has no matching '['");
            open.pop_back();
        }
    }
    if (!open.empty()) throw Error::input(source, "'[' at module " + std::to_string(open.back()) + " is never closed");
}

Turtle::Turtle(const Alphabet& alphabet, const TurtleOptions& options) : options_(options) {
    commands_.assign(alphabet.size(), Command::None);
    auto set = [&](std::string_view name, Command command) {
        const int id = alphabet.find(name);
        if (id >= 0) commands_[static_cast<std::size_t>(id)] = command;
    };
    set("F", Command::Forward);
    set("f", Command::Move);
    set("+", Command::Left);
    set("-", Command::Right);
    set("&", Command::PitchDown);
    set("^", Command::PitchUp);
    set("\\", Command::RollLeft);
    set("/", Command::RollRight);
    set("|", Command::TurnAround);
    set("$", Command::RollHorizontal);
    set("[", Command::Push);
    set("]", Command::Pop);
    set("!", Command::Width);
    set("SetHead", Command::SetHead);
    for (const auto& name : options_.leaf_modules) set(name, Command::Leaf);

    state_.position = options_.start;
    state_.width = options_.initial_width;
    const double root_width = options_.root_width.value_or(options_.initial_width);
    root_radius_set_ = options_.root_width.has_value();
    result_.tree.add_node(state_.position.cast<float>(), static_cast<float>(root_width * options_.radius_per_width), -1);
    result_.depth.push_back(0);
    result_.module.push_back(std::numeric_limits<std::uint32_t>::max());
    result_.drawn.push_back(0);
}

void Turtle::rotate(Eigen::Vector3d& a, Eigen::Vector3d& b, double degrees) {
    const double c = std::cos(degrees * kRadiansPerDegree), s = std::sin(degrees * kRadiansPerDegree);
    const Eigen::Vector3d a2 = a * c + b * s;
    b = b * c - a * s;
    a = a2;
}

void Turtle::apply(const ModuleString& string, std::size_t i) {
    const int symbol = string.symbol(i);
    const Command command =
            static_cast<std::size_t>(symbol) < commands_.size() ? commands_[static_cast<std::size_t>(symbol)] : Command::None;
    const double angle = string.param_or(i, options_.angle_deg);
    switch (command) {
        case Command::None:
            break;
        case Command::Forward:
            forward(string, i, true);
            break;
        case Command::Move:
            forward(string, i, false);
            break;
        case Command::Left:
            rotate(state_.heading, state_.left, angle);
            break;
        case Command::Right:
            rotate(state_.heading, state_.left, -angle);
            break;
        case Command::PitchDown:
            rotate(state_.heading, state_.up, -angle);
            break;
        case Command::PitchUp:
            rotate(state_.heading, state_.up, angle);
            break;
        case Command::RollLeft:
            rotate(state_.left, state_.up, angle);
            break;
        case Command::RollRight:
            rotate(state_.left, state_.up, -angle);
            break;
        case Command::TurnAround:
            state_.heading = -state_.heading;
            state_.left = -state_.left;
            break;
        case Command::RollHorizontal: {
            const Eigen::Vector3d left = Eigen::Vector3d::UnitZ().cross(state_.heading);
            // Undefined when heading straight up or down: keep the frame (as cpfg does).
            if (left.norm() > 1e-12) {
                state_.left = left.normalized();
                state_.up = state_.heading.cross(state_.left);
            }
            break;
        }
        case Command::Push:
            stack_.push_back(state_);
            ++state_.depth;
            break;
        case Command::Pop:
            if (stack_.empty()) throw Error::input("", "module string: ']' at module " + std::to_string(i) + " has no matching '['");
            state_ = stack_.back();
            stack_.pop_back();
            break;
        case Command::Width:
            if (string.param_count(i) == 0)
                state_.width *= options_.width_factor;
            else {
                const double w = string.params(i)[0];
                if (!(w >= 0.0)) throw Error::input("", "module string: " + module_text(string, i) + " sets a negative width");
                state_.width = w;
            }
            break;
        case Command::SetHead:
            set_heading(string.params(i), i);
            break;
        case Command::Leaf: {
            LeafPlacement leaf;
            leaf.position = state_.position.cast<float>();
            leaf.heading = state_.heading.cast<float>();
            leaf.up = state_.up.cast<float>();
            leaf.size = static_cast<float>(string.param_or(i, options_.leaf_size));
            leaf.node = state_.node;
            leaf.module = static_cast<std::uint32_t>(i);
            result_.leaves.push_back(leaf);
            break;
        }
    }
}

void Turtle::forward(const ModuleString& string, std::size_t i, bool draw) {
    const double length = string.param_or(i, options_.step);
    state_.position += length * state_.heading;
    const float radius = draw ? static_cast<float>(state_.width * options_.radius_per_width) : 0.0f;
    TreeGraph& tree = result_.tree;
    if (draw && state_.node == 0 && !root_radius_set_) {
        tree.nodes[0].radius = radius;  // the root takes the width of the first internode drawn from it
        root_radius_set_ = true;
    }
    const int parent = state_.node;
    const int node = tree.add_node(state_.position.cast<float>(), radius, parent);
    // Same bracket depth as the parent: this continues the parent's axis, so it is the main child.
    if (state_.depth == result_.depth[static_cast<std::size_t>(parent)]) {
        auto& children = tree.nodes[static_cast<std::size_t>(parent)].children;
        std::rotate(children.begin(), children.end() - 1, children.end());
    }
    result_.depth.push_back(state_.depth);
    result_.module.push_back(static_cast<std::uint32_t>(i));
    result_.drawn.push_back(draw ? 1 : 0);
    state_.node = node;
    if (draw) apply_tropism();
}

void Turtle::apply_tropism() {
    if (options_.elasticity == 0.0) return;
    const Eigen::Vector3d axis = state_.heading.cross(options_.tropism);
    const double s = axis.norm();
    if (s < 1e-12) return;  // heading parallel to T: no torque
    const Eigen::AngleAxisd rotation(options_.elasticity * s, axis / s);
    state_.heading = (rotation * state_.heading).normalized();
    // Re-orthonormalise so that thousands of bends do not let the frame drift.
    state_.left = (rotation * state_.left - (rotation * state_.left).dot(state_.heading) * state_.heading).normalized();
    state_.up = state_.heading.cross(state_.left);
}

void Turtle::set_heading(std::span<const double> p, std::size_t i) {
    if (p.size() != 3 && p.size() != 6)
        throw Error::input("", "module string: SetHead at module " + std::to_string(i) + " needs 3 or 6 parameters");
    const Eigen::Vector3d heading(p[0], p[1], p[2]);
    if (heading.norm() < 1e-12) throw Error::input("", "module string: SetHead at module " + std::to_string(i) + " has a zero heading");
    state_.heading = heading.normalized();
    // Keep U (or the given up vector) as close as possible: its component orthogonal to H.
    Eigen::Vector3d up = p.size() == 6 ? Eigen::Vector3d(p[3], p[4], p[5]) : state_.up;
    up -= up.dot(state_.heading) * state_.heading;
    if (up.norm() < 1e-9) {  // parallel to H: any perpendicular will do
        up = state_.heading.unitOrthogonal();
    }
    state_.up = up.normalized();
    state_.left = state_.up.cross(state_.heading);
}

TurtleResult interpret(const ModuleString& string, const TurtleOptions& options) {
    check_brackets(string, "");
    Turtle turtle(string.alphabet(), options);
    turtle.apply(string, 0, string.size());
    return turtle.take_result();
}

}  // namespace treelobes::lsystem
