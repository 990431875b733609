#include "synth/mesh_labels.hpp"

#include "geometry/union_find.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <optional>
#include <sstream>

namespace treelobes::synth {

namespace {

constexpr std::uint8_t kWood = 1, kLeaf = 0;

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

bool contains_any(const std::string& name, const std::vector<std::string>& words) {
    return std::any_of(words.begin(), words.end(), [&](const std::string& w) { return !w.empty() && name.find(w) != std::string::npos; });
}

// The label the names give, if any (material, then group, then object).
std::optional<std::uint8_t> label_by_name(const FaceNames& names, const std::vector<std::string>& leaf,
                                          const std::vector<std::string>& wood, bool default_wood) {
    for (const std::string* field : {&names.material, &names.group, &names.object}) {
        const std::string name = lower(*field);
        if (name.empty()) continue;
        if (contains_any(name, leaf)) return kLeaf;
        if (contains_any(name, wood)) return kWood;
    }
    if (default_wood && !names.empty()) return kWood;
    return std::nullopt;
}

double face_area(const TriangleMesh& mesh, const std::array<int, 3>& f) {
    const Eigen::Vector3d a = mesh.vertices[f[0]].cast<double>(), b = mesh.vertices[f[1]].cast<double>(),
                          c = mesh.vertices[f[2]].cast<double>();
    return 0.5 * (b - a).cross(c - a).norm();
}

// A part's area and the area-weighted scatter of its face normals. A leaf blade, flat or gently
// bent, single- or double-sided, has normals along one line (largest eigenvalue of the scatter
// near 1); a tube's normals turn around its axis (about 1/2), a solid's point everywhere (1/3).
// The vertices' spread would not do: a long, thin, curved twig tube lies in a plane too.
struct PartShape {
    double area = 0;
    Eigen::Matrix3d normals = Eigen::Matrix3d::Zero();

    void add_face(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
        const Eigen::Vector3d cross = (b - a).cross(c - a);
        const double twice_area = cross.norm();
        if (!(twice_area > 0)) return;
        area += 0.5 * twice_area;
        const Eigen::Vector3d n = cross / twice_area;
        normals += 0.5 * twice_area * n * n.transpose();
    }
    bool flat(double min_alignment) const {
        if (!(area > 0)) return true;  // degenerate slivers only: no surface either way
        const Eigen::Vector3d eigen = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(normals / area, Eigen::EigenvaluesOnly).eigenvalues();
        return eigen[2] >= min_alignment;
    }
};

// Labels the faces flagged in `pending` by the geometry of their connected parts.
void label_by_geometry(const TriangleMesh& mesh, const std::vector<bool>& pending, const MeshLabelOptions& o,
                       std::vector<std::uint8_t>& labels, MeshLabelReport& report) {
    UnionFind parts(mesh.vertices.size());
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        if (!pending[f]) continue;
        const auto& face = mesh.faces[f];
        parts.unite(face[0], face[1]);
        parts.unite(face[0], face[2]);
    }
    std::vector<int> part_of_root(mesh.vertices.size(), -1);
    std::vector<PartShape> shapes;
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        if (!pending[f]) continue;
        const auto& face = mesh.faces[f];
        int& part = part_of_root[parts.find(face[0])];
        if (part < 0) {
            part = static_cast<int>(shapes.size());
            shapes.emplace_back();
        }
        shapes[part].add_face(mesh.vertices[face[0]].cast<double>(), mesh.vertices[face[1]].cast<double>(),
                              mesh.vertices[face[2]].cast<double>());
    }
    double total_area = 0;
    for (const auto& face : mesh.faces) total_area += face_area(mesh, face);

    std::vector<std::uint8_t> part_label(shapes.size(), kWood);
    for (std::size_t p = 0; p < shapes.size(); ++p) {
        const bool leaf = shapes[p].area <= o.max_leaf_area_fraction * total_area && shapes[p].flat(o.min_normal_alignment);
        part_label[p] = leaf ? kLeaf : kWood;
        report.leaf_parts += leaf ? 1 : 0;
    }
    report.parts += shapes.size();
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        if (!pending[f]) continue;
        labels[f] = part_label[part_of_root[parts.find(mesh.faces[f][0])]];
        ++(labels[f] == kWood ? report.wood_by_geometry : report.leaf_by_geometry);
    }
}

}  // namespace

std::vector<std::string> parse_word_list(const std::string& text) {
    std::vector<std::string> words;
    std::stringstream stream(text);
    std::string item;
    while (std::getline(stream, item, ',')) {
        const auto first = item.find_first_not_of(" \t"), last = item.find_last_not_of(" \t");
        if (first != std::string::npos) words.push_back(lower(item.substr(first, last - first + 1)));
    }
    return words;
}

std::vector<std::uint8_t> label_faces(const NamedMesh& named, const MeshLabelOptions& options, MeshLabelReport* report) {
    const TriangleMesh& mesh = named.mesh;
    MeshLabelReport local;
    MeshLabelReport& r = report ? *report : local;
    r = {};
    std::vector<std::string> leaf, wood;
    for (const auto& w : options.leaf_words) leaf.push_back(lower(w));
    for (const auto& w : options.wood_words) wood.push_back(lower(w));

    // One decision per distinct name combination, then per face.
    std::vector<std::optional<std::uint8_t>> by_names;
    for (const auto& names : named.names) by_names.push_back(label_by_name(names, leaf, wood, options.named_faces_default_to_wood));
    std::vector<std::uint8_t> labels(mesh.faces.size(), kWood);
    std::vector<bool> pending(mesh.faces.size(), true);
    bool any_pending = false;
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
        const std::optional<std::uint8_t> label = named.face_names.empty() ? std::nullopt : by_names[named.face_names[f]];
        if (label) {
            labels[f] = *label;
            pending[f] = false;
            ++(*label == kWood ? r.wood_by_name : r.leaf_by_name);
        }
        any_pending = any_pending || pending[f];
    }
    if (any_pending) label_by_geometry(mesh, pending, options, labels, r);
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) (labels[f] == kWood ? r.wood_area : r.leaf_area) += face_area(mesh, mesh.faces[f]);
    return labels;
}

}  // namespace treelobes::synth
