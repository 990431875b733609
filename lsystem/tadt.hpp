// Tree abstract data type (tADT) of Lluch et al. 2010 (via Ong's seminar report, §3.1): the branching structure of
// a bracketed module string, one node per run of modules between brackets.
//
// Reading the string left to right: modules are added to the current node; '[' adds a lateral
// child and makes it current; ']' returns to the parent. A module that follows ']' starts a new
// *continuation* child of the node the bracket returned to (Lluch et al. 2010 appends it to the parent's
// list; splitting keeps every node one contiguous run, so the branches keep their position along
// the axis and the chain reproduces the geometry exactly). For `C1[C2[C3][C4]][C5]` both readings
// give the same five nodes. Children are in string order.
//
// Each node's length is the sum of its modules' lengths: the first parameter of modules listed in
// TadtOptions::length_modules (default F and f), or default_length when they have none; other
// modules count 0. subtree_length is the paper's "branching length": the node's length plus that
// of all its descendants (accumulated into the parent at each ']').
#pragma once

#include "lsystem/module_string.hpp"

#include <string>
#include <vector>

namespace treelobes::lsystem {

struct TadtOptions {
    std::vector<std::string> length_modules{"F", "f"};
    double default_length = 1.0;
};

struct TadtNode {
    std::size_t begin = 0;  // modules [begin, end) of the string; never a bracket
    std::size_t end = 0;
    int parent = -1;
    std::vector<int> children;  // string order
    bool lateral = false;       // opened by '[' (false: the root or a continuation after ']')
    double length = 0.0;
    double subtree_length = 0.0;
};

struct Tadt {
    ModuleString string;          // the string the nodes index into
    std::vector<TadtNode> nodes;  // node 0 is the root (possibly empty)
};

// Throws Error::input(source, ...) when brackets do not balance.
Tadt build_tadt(const ModuleString& string, const TadtOptions& options = {}, const std::string& source = "module string");

}  // namespace treelobes::lsystem
