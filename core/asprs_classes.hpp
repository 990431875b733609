// ASPRS point classes (LAS 1.4 R15, Table 17) as the tile pipeline reads them: which classes
// can never hold a tree's points, and their names for messages and summaries.
#pragma once

#include <cstdint>
#include <string>

namespace treelobes {

// Classes a survey gives to what is not vegetation: building (6), low and high noise (7, 18),
// water (9), rail (10), road surface (11), wire guard and conductor (13, 14), transmission tower
// (15), wire-structure connector (16), bridge deck (17), overhead structure (19), ignored ground
// (20), snow (21) and temporal exclusion (22). Never created (0), unclassified (1), ground (2:
// the terrain stage decides), the vegetation classes (3-5), the codes reserved in LAS 1.4 but
// used by older versions (8 model key-point, 12 overlap) and the user-definable 23-255 carry no
// such statement and may hold trees.
bool asprs_never_a_tree(std::uint8_t code);

// "building", "water", ... for the codes of asprs_never_a_tree and 0-5; "class N" otherwise.
std::string asprs_class_name(std::uint8_t code);

}  // namespace treelobes
