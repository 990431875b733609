// Branchlet patch library of a species (Livny et al. 2011, §5, Fig. 4, Appendix A).
//
// 20-30 complete branchlets per species are grown by the Appendix A patch L-system, applied
// directly (the rules are fixed; only the profile's parameters vary per species):
//   Seed(t, v)    -> a chain of #ChainPts segments Segment(t, v)
//   Segment(t, v) -> Edge(t, #Allometric) NewLeaf(v') Transf(v, #Phototropism, #Gravitropism) NewSeed(t', v')
//   NewSeed(t, v) -> if PlaceSeed(#InitThickness, #NumTwigs) Seed(t, v)
//   NewLeaf(v)    -> if PlaceLeaf(#NumLeaves) Leaf(v)
// Branchlets differ in root thickness (log-spaced over the range a lobe seed can have), in
// root elevation (horizontal to vertical) and in their random stream. Each branchlet is then
// partitioned into patches, one per chain: the chain's segments and leaves, with a docking
// point (position, orientation, thickness) wherever a child chain starts. Patches of
// terminal chains have no docking points and end the texturing (lobes/texturing.hpp).
#pragma once

#include "config/species_profile.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace treelobes::lobes {

struct PatchSegment {
    Eigen::Vector3f a{0, 0, 0}, b{0, 0, 0};
    float thickness_a = 0, thickness_b = 0;  // diameters (metres)
};

struct PatchLeaf {
    Eigen::Vector3f base{0, 0, 0};
    Eigen::Vector3f direction{0, 0, 1};  // along the blade
    Eigen::Vector3f normal{1, 0, 0};     // blade normal
    float length = 0.1f, width = 0.05f;
};

struct DockingPoint {
    Eigen::Vector3f position{0, 0, 0};
    Eigen::Vector3f direction{0, 0, 1};  // unit
    float thickness = 0;                 // diameter (metres)
};

// One patch, in a frame with its root at the origin.
struct Patch {
    float root_thickness = 0;                 // diameter at the root (metres)
    Eigen::Vector3f root_direction{0, 0, 1};  // unit
    std::vector<PatchSegment> segments;
    std::vector<PatchLeaf> leaves;  // shuffled: any prefix is a uniform subsample (LOD)
    std::vector<DockingPoint> docks;
    int branchlet = 0;     // the complete branchlet it was cut from
    float step = 0;        // segment length it was grown with (before simplifying)
    float length() const;  // along its segments
};

struct PatchLibraryOptions {
    int branchlets = 24;                // Livny et al. 2011: 20-30 per species
    double min_root_thickness = 0.004;  // metres
    double max_root_thickness = 0.08;
    double min_twig_thickness = 0.002;  // no seeds (docking points) thinner than this
    double segment_length = 4.0;        // segment length per unit root thickness of its chain
    // Douglas-Peucker tolerance of a chain's axis, per unit root thickness of the chain: nearly
    // collinear segments are merged once, so a patch draws fewer twig prisms (0 = off). Leaves and
    // docking points keep their grown positions, within this distance of the simplified axis.
    double simplify_tolerance = 1.0;
    std::uint64_t seed = 1;
};

struct PatchLibrary {
    std::string species;
    LeafShape leaf_shape = LeafShape::Broad;
    int leaf_cluster = 1;
    std::vector<Patch> patches;
    int branchlets = 0;
};

// Deterministic for (profile, options). Throws Error(Usage) for options out of range.
PatchLibrary build_patch_library(const SpeciesProfile& profile, const PatchLibraryOptions& options = {});

// Leaves of a patch drawn when a fraction of them is kept (stochastic pruning, LOD): the prefix
// of ceil(fraction * n) leaves of its shuffled list.
std::size_t kept_leaves(double fraction, std::size_t leaves);
// Triangles a placed patch adds to the synthesized mesh (lobes/synthesis.hpp): an open prism of
// `twig_sides` quads per segment and two per kept leaf. Texturing counts these against its budget.
std::size_t patch_triangles(const Patch& patch, int twig_sides, double leaf_share);

}  // namespace treelobes::lobes
