#include "core/off_mesh_io.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/obj_mesh_io.hpp"
#include "core/text_tokens.hpp"

#include <array>
#include <charconv>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

// The smallest vertex line ("0 0 0\n") and face line ("3 0 1 2\n"): a count above the file's
// size over these cannot be right, and is refused before anything is read.
constexpr std::size_t kShortestVertexLine = 6;
constexpr std::size_t kShortestFaceLine = 8;

class OffParser {
public:
    OffParser(std::string name, std::string text) : name_(std::move(name)), text_(std::move(text)) { result_.report.format = "off"; }

    NamedMesh parse() {
        std::string_view line = next_line("header");
        check_keyword(next_token(line));
        if (std::string_view rest = line; next_token(rest) == "BINARY") fail("binary OFF is not supported: convert it to PLY");
        if (line.empty()) line = next_line("counts");
        // Faces index vertices with int (TriangleMesh).
        const std::size_t most_vertices = std::min<std::size_t>(text_.size() / kShortestVertexLine, std::numeric_limits<int>::max());
        const std::size_t vertices = count(next_token(line), "vertex count", most_vertices);
        const std::size_t faces = count(next_token(line), "face count", text_.size() / kShortestFaceLine);
        read_vertices(vertices);
        read_faces(faces);
        return std::move(result_);
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw Error::input(name_, "OFF line " + std::to_string(line_number_) + ": " + what);
    }

    // The next line that holds more than a comment, without its comment.
    std::string_view next_line(const char* what) {
        while (position_ < text_.size()) {
            std::size_t end = text_.find('\n', position_);
            if (end == std::string::npos) end = text_.size();
            std::string_view line(text_.data() + position_, end - position_);
            position_ = end + 1;
            ++line_number_;
            line = trimmed(line.substr(0, line.find('#')));
            if (!line.empty()) return line;
        }
        throw Error::input(name_, std::string("OFF file ends before its ") + what + " (truncated file?)");
    }

    void check_keyword(std::string_view keyword) const {
        if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF") fail("the file does not start with OFF");
        const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
        if (prefix.find('4') != std::string_view::npos || prefix.find('n') != std::string_view::npos)
            fail("4D and n-dimensional OFF ('" + std::string(keyword.substr(0, 16)) + "') are not supported");
        if (prefix.find_first_not_of("STCN") != std::string_view::npos)
            fail("unknown OFF variant '" + std::string(keyword.substr(0, 16)) + "'");
    }

    std::size_t count(std::string_view token, const char* what, std::size_t most) const {
        if (token.empty()) fail(std::string(what) + " is missing");
        unsigned long long value = 0;
        const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
        if (error != std::errc() || end != token.data() + token.size() || value > most)
            fail(std::string(what) + " '" + std::string(token.substr(0, 32)) + "' is not a count the file can hold");
        return static_cast<std::size_t>(value);
    }

    int corner(std::string_view token, std::size_t face, std::size_t vertices) const {
        unsigned long long value = 0;
        const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
        if (error != std::errc() || end != token.data() + token.size() || value >= vertices)
            fail("face " + std::to_string(face) + " refers to vertex '" + std::string(token.substr(0, 32)) + "' but the file has " +
                 std::to_string(vertices) + " vertices (0-based)");
        return static_cast<int>(value);
    }

    double coordinate(std::string_view token, std::size_t vertex) const {
        double value = 0;
        const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
        if (token.empty()) fail("vertex " + std::to_string(vertex) + " has fewer than three coordinates");
        if (error != std::errc() || end != token.data() + token.size())
            fail("coordinate '" + std::string(token.substr(0, 32)) + "' is not a number");
        if (!std::isfinite(value)) fail("vertex " + std::to_string(vertex) + " has a NaN/inf coordinate");
        return value;
    }

    void read_vertices(std::size_t count) {
        if (count == 0) throw Error::input(name_, "no vertices (an empty OFF mesh)");
        auto& vertices = result_.mesh.vertices;
        vertices.reserve(count);
        for (std::size_t v = 0; v < count; ++v) {
            std::string_view line = next_line("vertices");
            Eigen::Vector3d p;
            for (int k = 0; k < 3; ++k) p[k] = coordinate(next_token(line), v);
            if (v == 0) result_.mesh.origin = mesh_origin_for(p);
            vertices.push_back((p - result_.mesh.origin).cast<float>());
        }
    }

    void read_faces(std::size_t count) {
        const std::size_t vertices = result_.mesh.vertices.size();
        for (std::size_t f = 0; f < count; ++f) {
            std::string_view line = next_line("faces");
            const std::size_t declared = this->count(next_token(line), "corner count", vertices);
            if (declared < 3) fail("face " + std::to_string(f) + " has fewer than 3 corners");
            corners_.clear();
            for (std::size_t k = 0; k < declared; ++k) {
                const std::string_view token = next_token(line);
                if (token.empty()) fail("face " + std::to_string(f) + " lists fewer corners than it declares");
                corners_.push_back(corner(token, f, vertices));
            }
            add_fan(corners_);
        }
    }

    // Polygons become triangle fans; a triangle with a repeated corner has no area and is dropped.
    void add_fan(const std::vector<int>& corners) {
        if (corners.size() > 3) ++result_.report.polygons_split;
        for (std::size_t k = 1; k + 1 < corners.size(); ++k) {
            const std::array<int, 3> f{corners[0], corners[k], corners[k + 1]};
            if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2])
                ++result_.report.degenerate_faces;
            else
                result_.mesh.faces.push_back(f);
        }
    }

    std::string name_;
    std::string text_;
    std::size_t position_ = 0;
    std::size_t line_number_ = 0;
    std::vector<int> corners_;
    NamedMesh result_;
};

}  // namespace

NamedMesh read_off(const fs::path& path) { return OffParser(path.string(), read_file(path)).parse(); }

}  // namespace treelobes
