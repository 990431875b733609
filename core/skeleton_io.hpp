// Skeleton PLY, the project's exchange format for TreeGraph (DESIGN.md):
//   element vertex N : float x, float y, float z, float radius
//   element edge M   : int vertex1, int vertex2   (parent -> child)
// Vertex 0 is the root. Written as binary little-endian by default; ASCII and binary are
// both read, and properties may come in any order. Positions are written in local
// coordinates; a non-zero origin goes into comment "origin x y z" and a georef sidecar.
#pragma once

#include "core/tree_graph.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace treelobes {

// `comments` receives the header comments (the origin comment included) when given.
TreeGraph read_skeleton_ply(const std::filesystem::path& path, std::vector<std::string>* comments = nullptr);
// `comments` are added to the header after the origin (decode records the chain code's
// parameters this way, encode/tree_code.hpp code_parameters_comment).
void write_skeleton_ply(const TreeGraph& tree, const std::filesystem::path& path, bool binary = true,
                        const std::vector<std::string>& comments = {});

}  // namespace treelobes
