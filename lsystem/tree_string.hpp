// TreeGraph -> bracketed module string, so that reconstructed trees (skeleton PLY) get the same
// tADT and multiresolution chain as L-system trees, and both representations can be compared on the same trees.
//
// Each internode parent -> child becomes `!(w)SetHead(dx,dy,dz)F(l)`: the child's width
// (2 * radius), its absolute direction and its length. Lateral children come first, each in
// brackets, then the main child (children[0]) continues the axis — the ABOP form `F[+F]F`. The
// turtle draws the string back into the same tree: same parent links, main child first, radii
// exactly, positions to float rounding (headings are absolute, so errors do not accumulate in
// angles). Interpret with the returned turtle options (start at the root, the root's radius).
#pragma once

#include "core/tree_graph.hpp"
#include "lsystem/module_string.hpp"
#include "lsystem/turtle.hpp"

namespace treelobes::lsystem {

struct TreeString {
    ModuleString modules;
    TurtleOptions turtle;  // start = root position, root_width = 2 * root radius, no tropism
};

// The tree must be valid (TreeGraph::validate); its origin is not part of the string.
TreeString tree_to_module_string(const TreeGraph& tree);

}  // namespace treelobes::lsystem
