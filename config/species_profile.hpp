// The full species profile of config/species.yaml: what config/species_library.hpp's
// SpeciesEntry carries (name, id, Livny et al. 2011, Table 1 parameters) plus
//   - a growth profile in the style of Weber & Penn 1995 ("Creation and rendering of
//     realistic trees"): crown shape, stem levels with branching angles, phyllotaxis
//     (rotate / whorl), curvature, tropism, taper, splitting, leaves — read by synth::grow;
//   - the branchlet patch profile of Livny et al. 2011, Appendix A (#ChainPts, #Phototropism, ...)
//     read by the patch L-system;
//   - ranges of natural variation (height, age, DBH) that synth samples per tree.
// docs/species.md (and the comments in species.yaml) explain every key; the loader in
// config/species_library.cpp rejects unknown keys and values outside the ranges below.
#pragma once

#include "config/species_library.hpp"

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace treelobes {

// Weber & Penn crown shapes: the length of a first-order branch relative to its maximum, as
// a function of where it sits in the crown (ShapeRatio of the paper).
enum class CrownShape { Conical, Spherical, Hemispherical, Cylindrical, TaperedCylindrical, Flame, InverseConical, TendFlame };

const char* crown_shape_name(CrownShape shape);
// ShapeRatio(shape, r) with r = 1 at the crown base and 0 at the top, in [0.2, 1] (Flame: [0, 1]).
double crown_shape_ratio(CrownShape shape, double r);

// How leaves are drawn: broad leaves are rhombi, needles thin strips, fronds' leaflets and
// compound leaves are groups of small rhombi (`cluster` per node).
enum class LeafShape { Broad, Needle, Leaflet };
const char* leaf_shape_name(LeafShape shape);

struct ValueRange {
    double min = 0.0;
    double max = 0.0;
};

// One stem level of Weber & Penn: level 0 is the trunk, level n+1 the branches on level n.
// Angles in degrees; `*_v` are the half-widths of uniform random variation.
struct StemLevel {
    // Placement on the parent (ignored for the trunk).
    double branches = 0;      // stems of this level per parent stem (level 1: on the trunk)
    double down_angle = 45;   // angle between the parent's and this stem's direction
    double down_angle_v = 0;  // < 0 (level 1 only): varies with the position along the trunk
    double rotate = 137.5;    // phyllotaxis: azimuth step between siblings; < 0 = alternate (180 ± |rotate|)
    double rotate_v = 0;
    int whorl = 1;       // stems per node (pine, Terminalia: tiers of 3-6 branches)
    double start = 0.1;  // levels >= 2: stems sit on the parent from this fraction of its length
                         // (bare inner crowns of pines); level 1 uses base_size
    // The stem itself.
    double length = 1.0;  // trunk: fraction of the tree height; others: max length relative to the parent
    double length_v = 0;
    double taper = 1.0;        // 0 = cylinder, 1 = cone to a point
    double taper_power = 1.0;  // radius ~ (1 - taper z)^taper_power: 1 cone, 0.5 paraboloid (forestry
                               // stem form: nearly cylindrical bole, fast taper near the top)
    int segments = 5;          // curve resolution (Weber & Penn CurveRes)
    double curve = 0;          // total bend along the stem
    double curve_back = 0;     // bend of the second half (S-shapes) when non-zero
    double curve_v = 0;        // random bend per stem (tortuous oak branches)
    double seg_splits = 0;     // dichotomous forks per segment (decurrent crowns)
    double split_angle = 0;
    double split_angle_v = 0;
    double tropism = 0;  // pull of the direction toward +z per stem (< 0: weeping, gravitropism)
};

struct LeafProfile {
    LeafShape shape = LeafShape::Broad;
    double per_branch = 0;  // leaf nodes on a last-level stem of maximum length (Weber & Penn Leaves)
    int cluster = 1;        // leaves per leaf node (needle fascicles, opposite leaflets, trifoliate)
    double length_m = 0.1;
    double width_m = 0.05;
    double size_v = 0.2;     // relative size variation
    double down_angle = 45;  // angle between twig and leaf
    double down_angle_v = 10;
    double face_up = 0.5;  // 0..1: how far the blade turns to face the sky (Livny et al. 2011, Appendix A: #FaceUp)
    double start = 0.3;    // leaves cover the stem from this fraction of its length to the tip
    int levels = 1;        // how many of the deepest stem levels carry leaves (pine shoots: 2)
    double lai = 0;        // leaf area index over the crown projection; 0 = as many leaves as per_branch says
};

struct GrowthProfile {
    CrownShape shape = CrownShape::Spherical;
    double base_size = 0.3;  // fraction of the height below the crown: no first-order branches there
    double base_size_v = 0.05;
    int base_splits = 0;            // trunks from the ground (multi-stemmed Lagerstroemia)
    double ratio_power = 1.5;       // child radius = parent radius at the fork * (child/parent length)^ratio_power
    double flare = 0.4;             // extra radius at the root collar
    double lean_v = 3;              // random lean of the trunk (degrees)
    double dead_crown = 0;          // lowest fraction of the crown with dead first-order branches: no
                                    // leaves, half their side branches (self-pruning of stand-grown pines)
    std::vector<StemLevel> levels;  // levels[0] = trunk; 2..4 levels
    LeafProfile leaves;
    double bark_reflectance = 0.45;  // at 1064 nm / 1550 nm, for scan intensities
    double leaf_reflectance = 0.55;
};

// Livny et al. 2011, Appendix A: the branchlet patch L-system's species profile.
struct PatchProfile {
    // Branch modeling
    int chain_pts = 15;
    double phototropism = 0.2;
    double gravitropism = 0.3;
    double allometric = 1.2;
    // Leaf modeling
    double leaf_phototropism = 0.2;
    double leaf_gravitropism = 0.7;
    double face_up = 0.9;
    // Branching control
    std::array<int, 2> branch_distr{1, 1};
    int num_twigs = 1;
    double branching_angle = 30;
    double spiral_angle = 180;
    double init_thickness = 1.0;
    // Leaf control
    std::array<int, 2> leaf_distr{1, 2};
    int num_leaves = 2;
    double leaf_angle = 40;
    double leaf_spiral_angle = 120;
    double orient_up = 0.8;
};

// Natural variation of individuals; synth samples height in the range and draws age and DBH
// correlated with it, so tall trees tend to be old and thick without being identical.
struct VariationProfile {
    ValueRange height_m;
    ValueRange age_years;
    ValueRange dbh_m;
};

struct SpeciesProfile {
    SpeciesEntry entry;
    bool reconstruction_from_table1 = false;  // false: the file's `defaults` were used
    std::string description;
    VariationProfile variation;
    GrowthProfile growth;
    PatchProfile patch;
};

// Loads and validates every species of a file. Throws Error(Usage) naming the file, the
// species and the key for unknown keys, missing keys, wrong types and out-of-range values;
// Error(InvalidInput) when the file is unreadable or not YAML.
std::vector<SpeciesProfile> load_species_profiles(const std::filesystem::path& file);

// Case-insensitive lookup as find_species(); throws Error(Usage) listing the known names.
const SpeciesProfile& find_species_profile(const std::vector<SpeciesProfile>& profiles, const std::string& name);

}  // namespace treelobes
