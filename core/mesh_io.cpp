// Mesh files: OBJ through core/obj_mesh_io.cpp and glb through core/glb_mesh_io.cpp (face
// names), OFF through core/off_mesh_io.cpp, PLY, STL and OM through OpenMesh. Points are read in double precision so georeferenced meshes keep their precision;
// the origin is moved into TriangleMesh::origin.
#include "core/mesh_io.hpp"

#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/glb_mesh_io.hpp"
#include "core/obj_mesh_io.hpp"
#include "core/off_mesh_io.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

struct DoubleTraits : OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
    using Normal = OpenMesh::Vec3d;
};
using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<DoubleTraits>;

bool is_mesh_extension(const std::string& ext) {
    return ext == "ply" || ext == "obj" || ext == "off" || ext == "stl" || ext == "om" || ext == "glb";
}

// OpenMesh reports problems on its own error stream; we turn them into one Error line.
void silence_openmesh() {
    omerr().disable();
    omlog().disable();
}

Eigen::Vector3d origin_for(const PolyMesh& mesh) {
    if (mesh.n_vertices() == 0) return Eigen::Vector3d::Zero();
    const auto& p = mesh.point(*mesh.vertices_begin());
    return mesh_origin_for(Eigen::Vector3d(p[0], p[1], p[2]));
}

// OpenMesh's PLY reader loops forever on a header it cannot parse (found by fuzz/mesh_fuzz.cpp:
// a header that never ends; a format line whose version is not a number, or is nan, inf or beyond
// a float, after which its stream fails and its keyword loop no longer advances). It reads the
// header word by word, so an obj_info line's words are keywords to it: "element" there made it
// spin the same way, "property" before any element crashed it. So the header is checked first: it
// starts with "ply", reaches end_header within 64 kB, and each line is a PLY header line with
// readable values, properties after an element and of PLY's types, and obj_info lines without
// header keywords.
void check_ply_header(const fs::path& path, const std::string& name) {
    std::ifstream in(path, std::ios::binary);
    static const std::set<std::string> kPlyTypes{"char", "uchar", "short", "ushort", "int",   "uint",   "float",   "double",
                                                 "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"};
    std::error_code size_error;
    const std::uintmax_t file_size = fs::file_size(path, size_error);
    std::string line;
    std::size_t read = 0;
    bool in_element = false;
    for (int number = 1; read < 65536 && std::getline(in, line); ++number) {
        read += line.size() + 1;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        std::istringstream words(line);
        std::vector<std::string> word{std::istream_iterator<std::string>(words), {}};
        const auto bad = [&](const std::string& what) {
            throw Error::input(name, "PLY header line " + std::to_string(number) + ": " + what);
        };
        const auto is_float = [](const std::string& text) {  // what OpenMesh reads the version into
            float value = 0;
            const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
            return error == std::errc() && end == text.data() + text.size() && std::isfinite(value);
        };
        if (number == 1) {
            if (line != "ply") bad("the file does not start with 'ply'");
            continue;
        }
        if (word.empty() || word[0] == "comment") continue;
        if (word[0] == "obj_info") {
            for (const char* keyword : {"element", "property", "end_header"})
                if (std::find(word.begin() + 1, word.end(), keyword) != word.end())
                    bad("obj_info holds the keyword '" + std::string(keyword) + "'");
            continue;
        }
        if (word[0] == "end_header") return;
        if (word[0] == "format") {
            if (word.size() != 3 || (word[1] != "ascii" && word[1] != "binary_little_endian" && word[1] != "binary_big_endian") ||
                !is_float(word[2]))
                bad("expected 'format ascii|binary_little_endian|binary_big_endian VERSION'");
        } else if (word[0] == "element") {
            std::uint64_t count = 0;
            const auto [end, error] = word.size() == 3 ? std::from_chars(word[2].data(), word[2].data() + word[2].size(), count)
                                                       : std::from_chars_result{nullptr, std::errc::invalid_argument};
            if (error != std::errc() || end != word[2].data() + word[2].size() || word[2][0] == '-') bad("expected 'element NAME COUNT'");
            // Every item of an element takes at least one byte of the body, in any encoding. OpenMesh
            // asked for 1.2 GB on a 1.3 kB file whose face count had 70 digits (fuzzing in CI).
            if (!size_error && count > file_size) bad("element '" + word[1].substr(0, 32) + "' has more items than the file has bytes");
            in_element = true;
        } else if (word[0] == "property") {
            // OpenMesh wrote through a null pointer on a property before any element (fuzzing, 60 s with seed 1).
            if (!in_element) bad("a property before any element");
            const bool list = word.size() > 1 && word[1] == "list";
            if (word.size() != (list ? 5u : 3u)) bad("expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'");
            for (std::size_t k = list ? 2 : 1; k + 1 < word.size(); ++k)
                if (!kPlyTypes.count(word[k])) bad("unknown property type '" + word[k].substr(0, 16) + "'");
        } else {
            bad("unknown keyword '" + word[0].substr(0, 32) + "'");
        }
    }
    throw Error::input(name, "PLY header has no end_header line");
}

// PLY, STL, OM. OpenMesh gives non-manifold faces their own vertex copies and skips
// faces with a repeated corner or a corner index out of range.
NamedMesh read_with_openmesh(const fs::path& path) {
    const std::string name = path.string();
    if (file_extension(path) == "ply") check_ply_header(path, name);
    silence_openmesh();
    PolyMesh mesh;
    OpenMesh::IO::Options options;
    if (!OpenMesh::IO::read_mesh(mesh, name, options)) throw Error::input(name, "cannot read mesh (malformed or truncated file)");

    NamedMesh named;
    named.report.format = file_extension(path);
    TriangleMesh& out = named.mesh;
    out.origin = origin_for(mesh);
    out.vertices.reserve(mesh.n_vertices());
    for (const auto& v : mesh.vertices()) {
        const auto& p = mesh.point(v);
        const Eigen::Vector3d q(p[0], p[1], p[2]);
        if (!q.allFinite()) throw Error::input(name, "vertex " + std::to_string(v.idx()) + " has a NaN/inf coordinate");
        out.vertices.push_back((q - out.origin).cast<float>());
    }
    for (const auto& f : mesh.faces()) {  // fan triangulation of polygons
        std::vector<int> corners;
        for (const auto& v : mesh.fv_range(f)) corners.push_back(v.idx());
        if (corners.size() > 3) ++named.report.polygons_split;
        for (std::size_t k = 1; k + 1 < corners.size(); ++k) out.faces.push_back({corners[0], corners[k], corners[k + 1]});
    }
    return named;
}

}  // namespace

NamedMesh read_named_mesh(const fs::path& path) {
    const std::string name = path.string();
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error::input(name, "no such file");
    if (fs::is_directory(path, ec)) throw Error::input(name, "is a directory, expected a mesh file");
    if (fs::file_size(path, ec) == 0) throw Error::input(name, "empty file");
    const std::string ext = file_extension(path);
    if (!is_mesh_extension(ext)) throw Error::input(name, "unknown mesh format (expected .obj, .glb, .ply, .off, .stl)");
    if (ext == "obj") return read_obj(path);
    if (ext == "glb") return read_glb(path);
    if (ext == "off") return read_off(path);
    return read_with_openmesh(path);
}

TriangleMesh read_mesh(const fs::path& path) { return read_named_mesh(path).mesh; }

void write_named_mesh(const NamedMesh& mesh, const fs::path& path) {
    if (file_extension(path) == "obj")
        write_obj(mesh, path);
    else
        write_mesh(mesh.mesh, path);
}

void write_mesh(const TriangleMesh& mesh, const fs::path& path) {
    const std::string ext = file_extension(path);
    if (ext != "ply" && ext != "obj" && ext != "off")
        throw Error::usage(path.string() + ": unknown mesh format '." + ext + "' (expected .ply, .obj, .off)");
    silence_openmesh();
    PolyMesh out;
    std::vector<PolyMesh::VertexHandle> handles;
    handles.reserve(mesh.vertices.size());
    for (const auto& v : mesh.vertices) handles.push_back(out.add_vertex(PolyMesh::Point(v.x(), v.y(), v.z())));
    for (const auto& f : mesh.faces) {
        for (int corner : f)
            if (corner < 0 || corner >= static_cast<int>(handles.size()))
                throw Error(ExitCode::Internal, "write_mesh: face refers to vertex " + std::to_string(corner));
        // A halfedge mesh cannot hold non-manifold configurations (leaf quads touching a
        // branch, for example): such a face gets its own copies of its corners instead of
        // being dropped, so the written geometry is complete.
        if (!out.add_face(handles[f[0]], handles[f[1]], handles[f[2]]).is_valid()) {
            std::array<PolyMesh::VertexHandle, 3> copies;
            for (int k = 0; k < 3; ++k) copies[k] = out.add_vertex(out.point(handles[f[k]]));
            out.add_face(copies[0], copies[1], copies[2]);
        }
    }
    OpenMesh::IO::Options options;
    if (ext == "ply") options += OpenMesh::IO::Options::Binary;
    write_atomically_via_path(path, [&](const fs::path& temporary) {
        if (!OpenMesh::IO::write_mesh(out, temporary.string(), options, 10)) throw Error::input(path.string(), "cannot write mesh");
    });
    write_georef_sidecar(path, mesh.origin, {});
}

}  // namespace treelobes
