// glTF 2.0 binary (.glb) of one or more trees, written directly (JSON chunk + BIN chunk;
// Khronos glTF 2.0 specification §4.4).
//
// Layout: glTF is y-up, so a point (x, y, z) of our z-up frame is stored as (x, z, -y), metres.
// Every tree is one node of the scene, translated from the scene origin to the tree's origin;
// its mesh has a "bark" primitive (branch tubes) and a "foliage" primitive (lobes or leaf cards,
// two-sided). Levels of detail use MSFT_lod: the scene node holds LOD 0 and lists the nodes of
// LODs 1.. (same translation, outside the scene) in extensions.MSFT_lod.ids, with
// extras.MSFT_screencoverage; viewers without the extension show LOD 0. The extension is
// declared in extensionsUsed, not extensionsRequired.
#pragma once

#include "export/tree_geometry.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace treelobes::exporting {

struct GltfTree {
    std::string name;
    Eigen::Vector3d origin{0, 0, 0};                     // world position of the tree's frame
    std::vector<TreeLod> lods;                           // LOD 0 first; mesh origins are ignored (tree frame)
    std::vector<std::pair<std::string, double>> extras;  // measures stored in the node's extras
    std::string species;
};

// The .glb bytes; positions relative to `scene_origin` (give it to the georef sidecar).
// Trees without any triangles at LOD 0 are left out; Error(InvalidInput) when none is left.
std::string glb_bytes(const std::vector<GltfTree>& trees, const Eigen::Vector3d& scene_origin);

}  // namespace treelobes::exporting
