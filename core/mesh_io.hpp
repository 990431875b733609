// Triangle-mesh files (PLY, OBJ, OFF) through OpenMesh, kept inside core/mesh_io.cpp.
#pragma once

#include "core/triangle_mesh.hpp"

#include <filesystem>

namespace treelobes {

// Polygons are fan-triangulated. Throws Error(InvalidInput) naming the file on failure.
TriangleMesh read_mesh(const std::filesystem::path& path);
// Format from the extension (.ply binary, .obj, .off); written atomically.
void write_mesh(const TriangleMesh& mesh, const std::filesystem::path& path);

}  // namespace treelobes
