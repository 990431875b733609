// Wood or leaf for every face of a CG tree model, the labels its samples carry
// (synth/mesh_sampling.hpp, `treelobes rebuild`).
//
// By name first: a face whose material, group or object name (checked in that order; the first
// name that matches decides) contains a leaf word is a leaf, one that contains a wood word is
// wood (case-insensitive substrings). With leaf words given by the user (`--leaf-materials`),
// they replace the default leaf words and every named face that matches none of them is wood.
//
// By geometry for the faces whose names say nothing (no names, or "Material.001"): the faces
// are split into parts (connected through shared vertices); leaves are small, flat and
// numerous, so a part is a leaf when it is flat (its face normals agree: the largest eigenvalue
// of their area-weighted scatter n n^T is at least min_normal_alignment; 1 for a plane, 1/2 for
// a tube, 1/3 for a solid) and small (its area below max_leaf_area_fraction of the whole mesh's). Everything else
// (tubes of branches, a trunk, a fused crown) is wood. A model whose leaves are welded onto the
// branches is one part and comes out as wood: name its materials or pass --leaf-materials.
#pragma once

#include "core/mesh_io.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace treelobes::synth {

struct MeshLabelOptions {
    std::vector<std::string> leaf_words{"leaf", "leaves", "foliage", "needle", "frond", "blatt", "laub"};
    std::vector<std::string> wood_words{"bark", "trunk", "branch", "wood", "stem", "twig", "stalk", "limb"};
    bool named_faces_default_to_wood = false;  // true with user leaf words: named faces matching none are wood
    double min_normal_alignment = 0.8;
    double max_leaf_area_fraction = 0.01;
};

struct MeshLabelReport {
    std::size_t wood_by_name = 0, leaf_by_name = 0;
    std::size_t wood_by_geometry = 0, leaf_by_geometry = 0;
    std::size_t parts = 0;                // connected parts of the faces labelled by geometry
    std::size_t leaf_parts = 0;           // of which leaves
    double wood_area = 0, leaf_area = 0;  // m^2
};

// One label per face: 1 wood, 0 leaf.
std::vector<std::uint8_t> label_faces(const NamedMesh& mesh, const MeshLabelOptions& options = {}, MeshLabelReport* report = nullptr);

// "Leaf,needles" -> {"leaf", "needles"}; blanks trimmed, empty items dropped.
std::vector<std::string> parse_word_list(const std::string& text);

}  // namespace treelobes::synth
