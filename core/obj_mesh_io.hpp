// Wavefront OBJ with the names of every face (materials, groups, objects), for
// core/mesh_io.cpp. CG tree models (Xfrog, SpeedTree exports) name bark and leaves by material
// or group; OpenMesh's OBJ reader drops those names, hence this small reader.
//
// Read: `v x y z [w|r g b]` (double precision), `f` with `i`, `i/t`, `i//n`, `i/t/n` corners
// (negative = relative to the last vertex), `usemtl`, `g`, `o`; `vt`, `vn`, `vp`, `s`, `l`,
// `mtllib` and the free-form curve records are skipped; a line ending in `\` continues.
#pragma once

#include "core/mesh_io.hpp"

#include <filesystem>

namespace treelobes {

NamedMesh read_obj(const std::filesystem::path& path);
void write_obj(const NamedMesh& mesh, const std::filesystem::path& path);

// The origin a reader subtracts from a mesh whose first vertex is `first`: per axis a round
// kilometre when the coordinate is georeferenced-sized (>= 10 km), zero otherwise.
Eigen::Vector3d mesh_origin_for(const Eigen::Vector3d& first);

}  // namespace treelobes
