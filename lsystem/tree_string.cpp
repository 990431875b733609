#include "lsystem/tree_string.hpp"

namespace treelobes::lsystem {

TreeString tree_to_module_string(const TreeGraph& tree) {
    TreeString result;
    ModuleString& s = result.modules;
    Alphabet& alphabet = s.alphabet();
    const int width = alphabet.intern("!"), set_head = alphabet.intern("SetHead"), forward = alphabet.intern("F");
    result.turtle.elasticity = 0.0;
    result.turtle.leaf_modules.clear();
    if (tree.nodes.empty()) return result;
    result.turtle.start = tree.nodes[0].position.cast<double>();
    result.turtle.root_width = 2.0 * tree.nodes[0].radius;

    auto emit_internode = [&](int child) {
        const TreeNode& node = tree.nodes[static_cast<std::size_t>(child)];
        const Eigen::Vector3d d = node.position.cast<double>() - tree.nodes[static_cast<std::size_t>(node.parent)].position.cast<double>();
        s.push_back(width, {2.0 * node.radius});
        const double length = d.norm();
        if (length > 0.0) s.push_back(set_head, {d.x(), d.y(), d.z()});  // a zero-length internode keeps H
        s.push_back(forward, {length});
    };

    // Explicit stack (skeletons can be thousands of nodes deep): visit = draw the internode to a
    // node, then its laterals in brackets, then its main child.
    enum class Action { Visit, Push, Pop };
    std::vector<std::pair<Action, int>> stack;
    auto expand = [&](int n) {
        const auto& children = tree.nodes[static_cast<std::size_t>(n)].children;
        if (children.empty()) return;
        stack.push_back({Action::Visit, children[0]});
        for (std::size_t k = children.size(); k-- > 1;) {
            stack.push_back({Action::Pop, 0});
            stack.push_back({Action::Visit, children[k]});
            stack.push_back({Action::Push, 0});
        }
    };
    expand(0);
    while (!stack.empty()) {
        const auto [action, node] = stack.back();
        stack.pop_back();
        if (action == Action::Push)
            s.push_back(Alphabet::kPush, {});
        else if (action == Action::Pop)
            s.push_back(Alphabet::kPop, {});
        else {
            emit_internode(node);
            expand(node);
        }
    }
    return result;
}

}  // namespace treelobes::lsystem
