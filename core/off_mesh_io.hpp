// Object File Format (Geomview's OFF, as in the Princeton Shape Benchmark), for core/mesh_io.cpp.
// OpenMesh's OFF reader sized its buffers from damaged counts (1.6 GB asked for a 1.7 kB file,
// twice, by fuzzing), so OFF has this small reader of its own.
//
// Read: a header keyword [ST][C][N]OFF, optionally followed on the same line by the counts;
// `V F [E]`; V vertex lines of x y z (double precision; colours, normals and texture coordinates
// after them are ignored); F face lines `n i1 .. in [colour]` with 0-based indices. '#' starts a
// comment. Binary OFF and the 4D and n-dimensional variants are refused.
#pragma once

#include "core/mesh_io.hpp"

#include <filesystem>

namespace treelobes {

NamedMesh read_off(const std::filesystem::path& path);

}  // namespace treelobes
