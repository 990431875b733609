#include "core/obj_mesh_io.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/log.hpp"
#include "core/text_tokens.hpp"

#include <charconv>
#include <cmath>
#include <map>
#include <string_view>
#include <tuple>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

// Records that carry nothing a tree rebuild needs.
bool is_skipped_record(std::string_view keyword) {
    static constexpr std::string_view kSkipped[] = {
            "vt",       "vp",         "s",         "l",     "p",     "mtllib", "usemap", "maplib", "lod",  "bevel", "c_interp",
            "d_interp", "shadow_obj", "trace_obj", "ctech", "stech", "mg",     "cstype", "deg",    "bmat", "step",  "curv",
            "curv2",    "surf",       "parm",      "trim",  "hole",  "scrv",   "sp",     "end",    "con",  "call",  "csh"};
    for (const auto s : kSkipped)
        if (keyword == s) return true;
    return false;
}

class ObjParser {
public:
    explicit ObjParser(std::string name) : name_(std::move(name)) { result_.report.format = "obj"; }

    NamedMesh parse(const std::string& text) {
        std::size_t start = 0;
        std::string joined;  // a logical line continued with '\'
        while (start < text.size()) {
            std::size_t end = text.find('\n', start);
            if (end == std::string::npos) end = text.size();
            ++line_number_;
            std::string_view line(text.data() + start, end - start);
            start = end + 1;
            const std::string_view body = trimmed(line);
            if (!body.empty() && body.back() == '\\') {
                joined.append(body.substr(0, body.size() - 1)).push_back(' ');
                continue;
            }
            if (!joined.empty()) {
                joined.append(body);
                parse_line(joined);
                joined.clear();
            } else {
                parse_line(line);
            }
        }
        if (!joined.empty()) parse_line(joined);
        return finish();
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw Error::input(name_, "line " + std::to_string(line_number_) + ": " + what);
    }

    double number(std::string_view token, const char* what) const {
        if (!token.empty() && token.front() == '+') token.remove_prefix(1);
        double value = 0;
        const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
        if (token.empty() || error != std::errc() || end != token.data() + token.size())
            fail(std::string("expected ") + what + ", got '" + std::string(token) + "'");
        return value;
    }

    void parse_line(std::string_view line) {
        const std::string_view keyword = next_token(line);
        if (keyword.empty() || keyword.front() == '#') return;
        if (keyword == "v") return vertex(line);
        if (keyword == "f" || keyword == "fo") return face(line);
        if (keyword == "vn") {
            ++result_.report.normals_ignored;
            return;
        }
        if (keyword == "usemtl") return rename(&FaceNames::material, line);
        if (keyword == "g") return rename(&FaceNames::group, line);
        if (keyword == "o") return rename(&FaceNames::object, line);
        if (is_skipped_record(keyword)) return;
        for (char c : keyword)
            if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126)
                fail("binary data where an OBJ record was expected (not an OBJ file?)");
        ++unknown_records_;
    }

    void vertex(std::string_view line) {
        Eigen::Vector3d p;
        for (int k = 0; k < 3; ++k) {
            const std::string_view token = next_token(line);
            if (token.empty()) fail("a vertex needs x y z (truncated file?)");
            p[k] = number(token, "a coordinate");
        }
        if (!p.allFinite()) fail("vertex " + std::to_string(positions_.size() + 1) + " has a NaN/inf coordinate");
        if (positions_.empty()) result_.mesh.origin = mesh_origin_for(p);
        positions_.push_back(p);
    }

    int corner_index(std::string_view token) const {
        const std::string_view index = token.substr(0, token.find('/'));
        long long value = 0;
        const auto [end, error] = std::from_chars(index.data(), index.data() + index.size(), value);
        if (index.empty() || error != std::errc() || end != index.data() + index.size() || value == 0)
            fail("bad face corner '" + std::string(token) + "'");
        const auto count = static_cast<long long>(positions_.size());
        const long long resolved = value > 0 ? value - 1 : count + value;
        if (resolved < 0 || resolved >= count)
            fail("face refers to vertex " + std::to_string(value) + " but only " + std::to_string(count) + " vertices are defined so far");
        return static_cast<int>(resolved);
    }

    void face(std::string_view line) {
        corners_.clear();
        for (std::string_view token = next_token(line); !token.empty(); token = next_token(line)) corners_.push_back(corner_index(token));
        if (corners_.size() < 3) fail("a face needs at least 3 corners (truncated file?)");
        if (corners_.size() > 3) ++result_.report.polygons_split;
        for (std::size_t k = 1; k + 1 < corners_.size(); ++k) {
            const std::array<int, 3> f{corners_[0], corners_[k], corners_[k + 1]};
            if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
                ++result_.report.degenerate_faces;
                continue;
            }
            result_.mesh.faces.push_back(f);
            face_names_.push_back(current_names_index());
        }
    }

    void rename(std::string FaceNames::*field, std::string_view rest) {
        current_.*field = std::string(trimmed(rest));
        current_index_ = -1;
    }

    std::uint32_t current_names_index() {
        if (current_index_ < 0) {
            const auto key = std::make_tuple(current_.material, current_.group, current_.object);
            const auto [it, inserted] = index_of_.emplace(key, static_cast<std::uint32_t>(result_.names.size()));
            if (inserted) result_.names.push_back(current_);
            current_index_ = static_cast<long long>(it->second);
        }
        return static_cast<std::uint32_t>(current_index_);
    }

    NamedMesh finish() {
        if (positions_.empty()) throw Error::input(name_, "no vertices (not an OBJ mesh?)");
        if (unknown_records_ > 0) log_warn(name_ + ": skipped " + std::to_string(unknown_records_) + " unknown OBJ records");
        auto& vertices = result_.mesh.vertices;
        vertices.reserve(positions_.size());
        for (const auto& p : positions_) vertices.push_back((p - result_.mesh.origin).cast<float>());
        result_.adopt_face_names(std::move(face_names_));
        return std::move(result_);
    }

    std::string name_;
    std::size_t line_number_ = 0;
    std::size_t unknown_records_ = 0;
    std::vector<Eigen::Vector3d> positions_;
    std::vector<int> corners_;
    std::vector<std::uint32_t> face_names_;
    FaceNames current_;
    long long current_index_ = -1;
    std::map<std::tuple<std::string, std::string, std::string>, std::uint32_t> index_of_;
    NamedMesh result_;
};

void append_float(std::string& out, float value) {
    char buffer[32];
    const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, value);
    out.append(buffer, end);
}

}  // namespace

Eigen::Vector3d mesh_origin_for(const Eigen::Vector3d& first) {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k)
        if (std::abs(first[k]) >= 1e4) origin[k] = std::round(first[k] / 1000.0) * 1000.0;
    return origin;
}

NamedMesh read_obj(const fs::path& path) { return ObjParser(path.string()).parse(read_file(path)); }

void write_obj(const NamedMesh& named, const fs::path& path) {
    const TriangleMesh& mesh = named.mesh;
    const bool has_names = !named.face_names.empty();
    if (has_names && named.face_names.size() != mesh.faces.size())
        throw Error(ExitCode::Internal, "write_obj: " + std::to_string(named.face_names.size()) + " face names for " +
                                                std::to_string(mesh.faces.size()) + " faces");
    std::string out = "# treelobes\n";
    out.reserve(40 * mesh.vertices.size() + 30 * mesh.faces.size());
    for (const auto& v : mesh.vertices) {
        out += "v ";
        append_float(out, v.x());
        out += ' ';
        append_float(out, v.y());
        out += ' ';
        append_float(out, v.z());
        out += '\n';
    }
    // Faces grouped by their names, groups in order of first use.
    std::vector<std::vector<std::size_t>> by_names(has_names ? named.names.size() : 1);
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        const std::uint32_t n = has_names ? named.face_names[f] : 0;
        if (n >= by_names.size()) throw Error(ExitCode::Internal, "write_obj: face name index out of range");
        by_names[n].push_back(f);
    }
    for (std::size_t n = 0; n < by_names.size(); ++n) {
        if (by_names[n].empty()) continue;
        if (has_names) {
            const FaceNames& names = named.names[n];
            if (!names.object.empty()) out += "o " + names.object + "\n";
            if (!names.group.empty()) out += "g " + names.group + "\n";
            if (!names.material.empty()) out += "usemtl " + names.material + "\n";
        }
        for (const std::size_t f : by_names[n]) {
            const auto& face = mesh.faces[f];
            out += "f " + std::to_string(face[0] + 1) + ' ' + std::to_string(face[1] + 1) + ' ' + std::to_string(face[2] + 1) + '\n';
        }
    }
    write_file_atomically(path, out);
    write_georef_sidecar(path, mesh.origin, {});
}

}  // namespace treelobes
