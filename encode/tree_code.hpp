// Tree skeleton <-> F6/DBF6 chain code (Strnad et al. 2020, §3.1, Eq. 1-2, Pseudocode 1).
//
// Internodes are the edges of the TreeGraph (parent -> child vertex). Positions are voxelized
// relative to the root vertex with voxel size d = l / r and v = rtz(p/d + sgn(p)/2) per axis;
// an internode's move is v(child) - v(parent), so quantization errors never accumulate.
//
// Traversal (Pseudocode 1): from the root, follow the main child at every fork at once and queue
// the laterals; at a tip continue with the front of the queue. The main child is the child with
// the largest coded radius; ties go to the smallest direction change with respect to the incoming
// internode, then to the lowest node index. Laterals come in the same order (decreasing radius).
// The order is computed from the coded (quantized) radii and voxel moves, so decoding and
// encoding again reproduces the code exactly. Multi-way forks with k laterals: when the first
// lateral starts, one zero-length internode per remaining sibling is emitted (empty move, 6,
// carrying the first lateral's radius) and the sibling is queued. A root with several children
// starts with one such zero-length internode carrying the trunk's radius. A branch's first
// vertex that falls into its parent's voxel and is not a tip is merged into the parent before
// coding (its zero-length internode would read as such a fork code), so every code decodes to
// exactly the tree it codes and encode -> decode -> encode is the identity on codes.
#pragma once

#include "core/tree_graph.hpp"
#include "encode/chain_code.hpp"

#include <optional>
#include <string>
#include <vector>

namespace treelobes::encode {

struct EncodeOptions {
    double resolution = 5.0;        // r: voxels spanned by an axis-aligned internode of length l
    double internode_length = 0.0;  // l in metres; 0 = median edge length of the skeleton
    double radius_unit = 0.001;     // metres per radius step of R (1 mm)
    CodeKind kind = CodeKind::DBF6;
};

// What a decoder needs besides C and R.
struct CodeGeometry {
    double voxel_size = 0.0;                 // d = l / r in metres
    double radius_unit = 0.001;              // metres per radius step
    int root_radius = 0;                     // root vertex radius in radius units
    Eigen::Vector3f root_position{0, 0, 0};  // local coordinates of the root vertex
    Eigen::Vector3d origin{0, 0, 0};         // TreeGraph::origin of the tree
};

struct EncodedTree {
    ChainCode code;
    CodeGeometry geometry;
    double resolution = 0.0;
    double internode_length = 0.0;      // l actually used (the median edge length when auto)
    std::vector<Internode> internodes;  // the stream in code order (write_symbols gives either kind)
    // Node of the input tree behind each node of the decoded tree (index 0 = the root), so
    // decoded and original vertices can be compared one to one.
    std::vector<int> decoded_to_source;
};

// Encodes a tree. Throws Error(Usage) for a non-positive resolution, internode length or
// radius unit, Error(InvalidInput) naming `context` for an invalid tree, a tree without
// internodes, negative radii, or coordinates too far from the root for the voxel size.
EncodedTree encode_tree(const TreeGraph& tree, const EncodeOptions& options, const std::string& context = "tree");

// Decodes C and R into a tree with voxel-centre positions and radius = R * radius unit; the
// children of every vertex come main child first. Zero-length internodes that code forks are
// contracted (chain_code.hpp contracted_internodes). Throws Error(InvalidInput) naming `context`
// for a corrupt code or radius list, Error(Usage) for a non-positive voxel size or radius unit.
TreeGraph decode_tree(const ChainCode& code, const CodeGeometry& geometry, const std::string& context = "chain code");

// decode_tree for a code in internode form (same tree, same checks of the structure and of
// every value; errors name internodes instead of characters).
TreeGraph decode_internodes(const InternodeVectors& code, const CodeGeometry& geometry, const std::string& context = "chain code");

// The parameters a decoded skeleton records in its PLY header (comment "treelobes_code
// resolution R internode_length L radius_unit U", shortest decimals that read back exactly), so
// that `encode` can use them when no option overrides them: encode -> decode -> encode with
// the same options then reproduces the code byte for byte.
struct CodeParameters {
    double resolution = 0.0;
    double internode_length = 0.0;
    double radius_unit = 0.0;
};
std::string code_parameters_comment(const CodeParameters& parameters);
// The parameters of the first such comment; none when there is none. Throws Error(InvalidInput)
// naming `context` for a comment whose values are not positive finite numbers.
std::optional<CodeParameters> find_code_parameters(const std::vector<std::string>& comments, const std::string& context);

// Median length of the non-zero edges: the internode length l of a resampled skeleton.
// Throws Error(InvalidInput) when the tree has no edge of positive length.
double median_internode_length(const TreeGraph& tree, const std::string& context = "tree");

// Eq. 1 for one coordinate already divided by d: round half away from zero.
std::int64_t voxelize(double coordinate_in_voxels);

// Radius in radius units (rounded), as stored in R.
int quantize_radius(float radius, double radius_unit);

}  // namespace treelobes::encode
