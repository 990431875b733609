// glTF 2.0 binary (.glb) meshes for core/mesh_io.cpp, read after the Khronos glTF 2.0
// specification (no library: Debian packages none that reads glTF).
//
// Read: the default scene (`scene`, else scene 0, else every root node) through the node
// hierarchy, each node's `matrix` or translation/rotation/scale composed in double precision;
// primitives of mode TRIANGLES (the default), TRIANGLE_STRIP and TRIANGLE_FAN, indexed
// (unsigned byte, short or int) or not; POSITION as VEC3 of float or, as KHR_mesh_quantization
// allows, of (unsigned) byte or short, normalized or not; byteOffset and byteStride. The buffer
// must be the GLB's BIN chunk (buffer 0 without uri). The extensions KHR_mesh_quantization,
// KHR_texture_transform, KHR_texture_basisu, EXT_texture_webp, EXT_texture_avif and
// KHR_materials_* may be required (the last four only change the look).
// Skipped and counted in MeshReadReport::primitives_skipped: points and lines primitives, and
// primitives without POSITION. Ignored: normals, texture coordinates, skins (the mesh is read in
// its rest pose), morph targets, cameras, animations, nodes outside the scene (MSFT_lod levels).
// Refused with one line naming the file: external or data: URI buffers ("pack the model as a
// self-contained .glb"), sparse accessors, any other required extension (Draco, meshopt...),
// a node hierarchy with a cycle, a shared node or more than 1000 levels, an index, offset, count
// or stride outside its chunk, NaN/inf positions, and a scene without any triangle.
//
// Frames: glTF is y-up (§3.4), treelobes z-up; a glTF point (x, y, z) is our (x, -z, y), the
// inverse of export/gltf.cpp. A "<stem>.georef.json" sidecar's origin (written by `treelobes
// export`) is added back, so an exported scene reads back in its original coordinates.
//
// Names (FaceNames, which synth/mesh_labels.hpp reads for bark and leaf words): material = the
// primitive's material `name`, group = the mesh `name`, object = the node `name`.
#pragma once

#include "core/mesh_io.hpp"

#include <filesystem>

namespace treelobes {

NamedMesh read_glb(const std::filesystem::path& path);

}  // namespace treelobes
