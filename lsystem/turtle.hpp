// Turtle interpretation of module strings (ABOP ch. 1.5, 2.2) into a TreeGraph and leaf
// placements.
//
// The turtle has a position and an orthonormal frame H (heading), L (left), U (up), H x L = U.
// It starts at `TurtleOptions::start` with H = +z (up), L = +y, U = -x. Commands (angles in
// degrees; a module without parameter uses TurtleOptions::step / angle_deg):
//   F(l)  move l along H and draw: a new TreeGraph node, child of the current node
//   f(l)  move l without drawing: the tree must stay connected, so a node of radius 0 is added
//         and flagged `drawn = 0`
//   +(a) -(a)   turn left / right about U        &(a) ^(a)   pitch down / up about L
//   \(a) /(a)   roll left / right about H        |           turn around (180 deg about U)
//   $           roll about H until L is horizontal (ABOP: L = V x H / |V x H|, V = +z)
//   [ ]         push / pop the turtle state      !(w)        set the width; `!` alone multiplies
//                                                            it by width_factor
//   SetHead(hx,hy,hz)            set H (L-Py); U is kept as close as possible
//   L(s) (TurtleOptions::leaf_modules)  record a leaf of size s at the turtle (no movement)
// Other modules are ignored. Tropism (ABOP eq. 2.4): after every F the frame turns about H x T
// by elasticity * |H x T| radians, bending branches toward T.
//
// Node radius = width * radius_per_width (ABOP widths are diameters). The root's radius is
// root_width (if set), else the width of the first internode drawn from it.
// Children are ordered main child first: a node drawn at the same bracket depth as its parent
// continues the parent's axis and is put first; nodes opened by '[' are laterals, in string order.
#pragma once

#include "core/tree_graph.hpp"
#include "lsystem/module_string.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace treelobes::lsystem {

struct TurtleOptions {
    double step = 1.0;                        // F and f without parameter
    double angle_deg = 45.0;                  // + - & ^ \ / without parameter
    double initial_width = 1.0;               // width before the first '!'
    double width_factor = 0.7;                // '!' without parameter multiplies the width by this
    double radius_per_width = 0.5;            // widths are diameters: radius = width / 2
    std::optional<double> root_width;         // root radius = root_width * radius_per_width when set
    Eigen::Vector3d tropism{0.0, 0.0, -1.0};  // T, the direction branches bend toward (gravity)
    double elasticity = 0.0;                  // e of ABOP; 0 = no tropism
    Eigen::Vector3d start{0.0, 0.0, 0.0};     // root position (local coordinates)
    std::vector<std::string> leaf_modules{"L"};
    double leaf_size = 1.0;  // leaf module without parameter
};

// A leaf recorded by the turtle (for foliage meshes and the foliage box hierarchy, Lluch et al. 2010, via Ong's seminar report, §3.2).
struct LeafPlacement {
    Eigen::Vector3f position{0, 0, 0};
    Eigen::Vector3f heading{0, 0, 1};  // H at the leaf: the blade's direction
    Eigen::Vector3f up{-1, 0, 0};      // U at the leaf: the blade's normal
    float size = 1.0f;                 // first parameter of the leaf module
    int node = 0;                      // TreeGraph node the leaf grows from
    std::uint32_t module = 0;          // index of the leaf module in the interpreted string
};

struct TurtleResult {
    TreeGraph tree;
    std::vector<int> depth;             // per node: bracket depth at which it was drawn
    std::vector<std::uint32_t> module;  // per node: index of its F/f module (root: UINT32_MAX)
    std::vector<unsigned char> drawn;   // per node: 1 for F, 0 for f and the root
    std::vector<LeafPlacement> leaves;
};

// The turtle as a step-by-step machine, for callers that interpret a string out of order (the
// multiresolution chain restores saved states instead of popping brackets).
class Turtle {
public:
    struct State {
        Eigen::Vector3d position{0, 0, 0};
        Eigen::Vector3d heading{0, 0, 1};
        Eigen::Vector3d left{0, 1, 0};
        Eigen::Vector3d up{-1, 0, 0};
        double width = 1.0;
        int node = 0;   // current TreeGraph node
        int depth = 0;  // bracket depth
    };

    // Resolves the turtle commands of `alphabet` once; the root node is created here.
    Turtle(const Alphabet& alphabet, const TurtleOptions& options);

    // Interprets module i of `string` (which must use the alphabet given to the constructor).
    // Throws Error::input for ']' without '[' and for negative widths.
    void apply(const ModuleString& string, std::size_t i);
    void apply(const ModuleString& string, std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) apply(string, i);
    }
    // Starts a lateral branch without saving the state (what '[' does besides pushing).
    void enter_lateral() { ++state_.depth; }

    const State& state() const { return state_; }
    void set_state(const State& state) { state_ = state; }
    std::size_t open_brackets() const { return stack_.size(); }

    const TurtleResult& result() const { return result_; }
    TurtleResult take_result() { return std::move(result_); }

private:
    enum class Command : unsigned char {
        None,
        Forward,
        Move,
        Left,
        Right,
        PitchDown,
        PitchUp,
        RollLeft,
        RollRight,
        TurnAround,
        RollHorizontal,
        Push,
        Pop,
        Width,
        SetHead,
        Leaf,
    };

    void forward(const ModuleString& string, std::size_t i, bool draw);
    void rotate(Eigen::Vector3d& a, Eigen::Vector3d& b, double degrees);
    void apply_tropism();
    void set_heading(std::span<const double> p, std::size_t i);

    TurtleOptions options_;
    std::vector<Command> commands_;  // by symbol id
    State state_;
    std::vector<State> stack_;
    TurtleResult result_;
    bool root_radius_set_ = false;
};

// Interprets a whole string. Brackets must balance (Error::input otherwise).
TurtleResult interpret(const ModuleString& string, const TurtleOptions& options = {});

// Throws Error::input(source, ...) naming the module index when '[' and ']' do not balance.
void check_brackets(const ModuleString& string, const std::string& source);

}  // namespace treelobes::lsystem
