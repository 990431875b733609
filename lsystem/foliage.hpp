// Foliage of the hybrid multiresolution representation (Lluch et al. 2010, via Ong's seminar report, §3.2): leaf
// blades as triangles, and the bounding-box hierarchy of the foliage that follows the branching.
//
// The hierarchy has one box per tADT node whose subtree carries foliage: the root box bounds all
// leaves, a node's children bound the foliage of its sub-branches (its lateral branches and the
// continuation of its axis). Brackets without any length module (no F/f: a leaf `[&(60)L]`, a
// whorl) are not sub-branches but ornaments of their node: their leaves count as the node's own
// leaves and they get no box. A node without own leaves whose foliage all sits in one child has
// the same box as that child and shares it (FoliageHierarchy::box_of_node), so chains of leafless
// internodes do not repeat boxes and textures. Because every tADT subtree is one contiguous run of
// the string, every box's leaves are one contiguous range of the turtle's leaves (string order).
//
// Boxes bound the leaf blades (not just their bases). Each side is at least min_side_fraction of
// the root box's largest side, so a single flat leaf still has a volume and six usable planes.
// A box is textured when volume / root volume > texture_threshold (the root,
// ratio 1, is textured for every threshold < 1): small boxes are left to their ancestors' textures.
#pragma once

#include "core/triangle_mesh.hpp"
#include "lsystem/multires_chain.hpp"
#include "lsystem/tadt.hpp"
#include "lsystem/turtle.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace treelobes::lsystem {

struct LeafShape {
    double width_ratio = 0.5;  // blade width / blade length (the leaf's size)
};

// The blade of a leaf: a hexagon from the leaf's base along H (length = size), widest (width_ratio
// * size) at 40 % of its length, lying in the plane of H and L (normal U). Base first.
std::array<Eigen::Vector3f, 6> leaf_outline(const LeafPlacement& leaf, const LeafShape& shape = {});

// Leaves [begin, end) as a triangle mesh (4 triangles per blade), in the leaves' local coordinates.
TriangleMesh foliage_mesh(std::span<const LeafPlacement> leaves, const LeafShape& shape = {});

struct FoliageOptions {
    LeafShape shape;
    double texture_threshold = 0.01;  // texture boxes with volume ratio above this (0 <= t < 1)
    double min_side_fraction = 0.01;  // smallest box side, as a fraction of the root's largest side
};

struct FoliageBox {
    Eigen::AlignedBox3d box;                   // local coordinates of the turtle (TreeGraph::origin not included)
    int tadt_node = 0;                         // the deepest tADT node with this foliage (the box's own node)
    int parent = -1;                           // box index, -1 for the root box
    std::vector<int> children;                 // box indices, string order
    int depth = 0;                             // 0 for the root box
    std::size_t leaf_begin = 0, leaf_end = 0;  // range of TurtleResult::leaves
    std::size_t own_leaves = 0;                // leaves of the tADT node itself and its ornaments (not in sub-branches)
    double volume_ratio = 0.0;                 // box volume / root box volume
    bool textured = false;

    std::size_t leaf_count() const { return leaf_end - leaf_begin; }
};

struct FoliageHierarchy {
    std::vector<FoliageBox> boxes;                                 // box 0 is the root box; parents before children
    std::vector<int> box_of_node;                                  // per tADT node: its box, -1 without leaves or for an ornament
    std::vector<char> ornament;                                    // per tADT node: a bracket without length modules (see above)
    std::vector<std::pair<std::size_t, std::size_t>> node_leaves;  // per tADT node: its subtree's leaf range
    std::size_t leaf_count = 0;

    bool empty() const { return boxes.empty(); }
    std::size_t textured_count() const;
    int max_depth() const;
};

// `leaves` must come from interpreting tadt.string (TurtleResult::leaves, in string order).
// Throws Error::usage for a threshold outside [0, 1) or a negative side fraction, Error::input when
// the leaves do not belong to the string (module index out of range or out of order).
FoliageHierarchy build_foliage_hierarchy(const Tadt& tadt, std::span<const LeafPlacement> leaves, const FoliageOptions& options = {});

// Foliage of a combined level (Lluch et al. 2010, via Ong's seminar report, §3.3): the chain prefix draws its own leaves as geometry,
// and so are the ornaments of its nodes (the greedy chain reaches those zero-length nodes last, but
// a leaf belongs with its branch). Every sub-branch the prefix has not reached yet is drawn with the
// textures of its box when that box is textured; a sub-branch below the texture threshold has no
// textures, and the caller either draws its leaves as geometry or omits them (small_boxes).
struct FoliageLod {
    std::vector<std::size_t> attached_leaves;  // leaves of unvisited ornaments of visited nodes
    std::vector<int> textured_boxes;           // boxes standing in for unvisited sub-branches
    std::size_t leaves_in_textures = 0;
    std::vector<int> small_boxes;  // unvisited sub-branches without textures
    std::size_t leaves_in_small_boxes = 0;
};

// `visited` holds one flag per tADT node (1 = in the chain prefix), e.g. from visited_nodes().
FoliageLod foliage_for_prefix(const Tadt& tadt, const FoliageHierarchy& hierarchy, const std::vector<char>& visited);

// The foliage-only level of detail (Lluch et al. 2010, via Ong's seminar report, §3.3: "each further level in the bounding box hierarchy
// represents the next LOD"): the textured boxes that stand for the whole crown at hierarchy depth
// `depth`. Starting from the root box, a box is replaced by its children while it is shallower than
// `depth`, has no own leaves and all its children are textured, so every cut covers every leaf
// exactly once. Boxes in hierarchy order; empty for a hierarchy without leaves.
std::vector<int> foliage_cut(const FoliageHierarchy& hierarchy, int depth);

// Per tADT node: 1 when one of the first `end` chain entries is that node.
std::vector<char> visited_nodes(const MultiresChain& chain, std::size_t end);

}  // namespace treelobes::lsystem
