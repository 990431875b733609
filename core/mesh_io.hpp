// Triangle-mesh files. One reading entry point, read_named_mesh(), chooses the reader by the
// extension: OBJ through core/obj_mesh_io.cpp (OpenMesh's OBJ reader does not give the group and
// material of each face, which tell bark from leaves in CG tree models), glTF 2.0 binary (.glb)
// through core/glb_mesh_io.cpp, PLY, OFF and STL through OpenMesh (kept inside
// core/mesh_io.cpp). read_mesh() is the same without the names.
#pragma once

#include "core/triangle_mesh.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace treelobes {

// The names a face carries in its file: OBJ material (`usemtl`), group (`g`) and object (`o`);
// glTF material, mesh and node names (core/glb_mesh_io.hpp); empty when absent.
struct FaceNames {
    std::string material, group, object;
    bool empty() const { return material.empty() && group.empty() && object.empty(); }
    bool operator==(const FaceNames&) const = default;
};

// What the reader repaired or dropped on the way.
struct MeshReadReport {
    std::string format;                  // "obj", "ply", "off", "stl", "glb"
    std::size_t polygons_split = 0;      // faces with more than three corners, fan-triangulated
    std::size_t degenerate_faces = 0;    // dropped: a corner repeated (no area, nothing to sample)
    std::size_t normals_ignored = 0;     // normal records in the file (normals are recomputed where needed)
    std::size_t primitives_skipped = 0;  // glTF points and lines primitives, and primitives without positions
};

struct NamedMesh {
    TriangleMesh mesh;                      // local coordinates + double origin (UTM-sized input keeps its precision)
    std::vector<FaceNames> names;           // distinct name combinations, in order of first use
    std::vector<std::uint32_t> face_names;  // per face an index into `names`; empty when the file names no face
    MeshReadReport report;

    // Takes the readers' per-face name indices when some name is not empty; otherwise the file
    // names no face, and `names` and `face_names` are left empty.
    void adopt_face_names(std::vector<std::uint32_t>&& per_face) {
        bool named = false;
        for (const FaceNames& n : names) named = named || !n.empty();
        if (named)
            face_names = std::move(per_face);
        else
            names.clear();
    }
};

// Polygons are fan-triangulated, faces with a repeated corner dropped, non-manifold edges kept
// (each face stays a face). Throws Error(InvalidInput) naming the file (and the line for OBJ) for
// a missing, empty, truncated or malformed file, a face naming a vertex that does not exist and
// a NaN/inf coordinate (and for .glb what core/glb_mesh_io.hpp lists as refused).
NamedMesh read_named_mesh(const std::filesystem::path& path);
TriangleMesh read_mesh(const std::filesystem::path& path);

// Format from the extension (.ply binary, .obj, .off); written atomically.
void write_mesh(const TriangleMesh& mesh, const std::filesystem::path& path);
// An OBJ that keeps the names: faces grouped by their FaceNames (`o`, `g`, `usemtl` lines).
// Other extensions write the geometry only (write_mesh).
void write_named_mesh(const NamedMesh& mesh, const std::filesystem::path& path);

}  // namespace treelobes
