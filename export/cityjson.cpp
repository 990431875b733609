#include "export/cityjson.hpp"

#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/version.hpp"
#include "export/tree_measures.hpp"
#include "geometry/branch_mesh.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <map>
#include <set>

namespace treelobes::exporting {

namespace {

using nlohmann::json;

constexpr double kScale = 0.001;  // metres per vertex unit

double millimetres(double value) { return std::round(value * 1000.0) / 1000.0; }

// Integer vertices on the millimetre grid, each stored once.
class VertexGrid {
public:
    explicit VertexGrid(const Eigen::Vector3d& translate) : translate_(translate) {}

    int index(const Eigen::Vector3d& world) {
        const std::array<long long, 3> key = {std::llround((world.x() - translate_.x()) / kScale),
                                              std::llround((world.y() - translate_.y()) / kScale),
                                              std::llround((world.z() - translate_.z()) / kScale)};
        const auto [it, fresh] = index_.try_emplace(key, static_cast<int>(vertices_.size()));
        if (fresh) vertices_.push_back(key);
        return it->second;
    }
    // Triangles of `mesh` as rings [[a, b, c]]; collapsed ones left out.
    json surfaces(const TriangleMesh& mesh) {
        json out = json::array();
        for (const auto& f : mesh.faces) {
            std::array<int, 3> ring{};
            for (int k = 0; k < 3; ++k) ring[k] = index(mesh.origin + mesh.vertices[f[k]].cast<double>());
            if (ring[0] != ring[1] && ring[1] != ring[2] && ring[0] != ring[2]) out.push_back(json::array({ring}));
        }
        return out;
    }
    json vertices() const {
        json out = json::array();
        for (const auto& v : vertices_) out.push_back(v);
        return out;
    }
    // Real coordinates relative to the translate, in metres (the "vertices-templates" form).
    json vertices_in_metres() const {
        json out = json::array();
        for (const auto& v : vertices_) out.push_back({millimetres(v[0] * kScale), millimetres(v[1] * kScale), millimetres(v[2] * kScale)});
        return out;
    }
    bool empty() const { return vertices_.empty(); }

private:
    Eigen::Vector3d translate_;
    std::map<std::array<long long, 3>, int> index_;
    std::vector<std::array<long long, 3>> vertices_;
};

// Below every node widened by its radius and every lobe vertex, so vertex integers are >= 0.
Eigen::Vector3d minimum_corner(const std::vector<ExportTree>& trees) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
    for (const auto& tree : trees) {
        for (const auto& node : tree.skeleton.nodes)
            lo = lo.cwiseMin(tree.skeleton.origin + (node.position.array() - node.radius).matrix().cast<double>());
        for (const auto& lobe : tree.lobes)
            for (const auto& v : lobe.vertices) lo = lo.cwiseMin(lobe.origin + v.cast<double>());
    }
    return lo.array().floor().matrix();
}

// The LoD 2 geometry: branch tubes and lobes, origin = the tree's origin.
TriangleMesh lod2_mesh(const ExportTree& tree, const CityJsonOptions& options) {
    BranchMeshOptions tubes;
    tubes.sides = options.branch_sides;
    tubes.subdivisions = 1;
    TriangleMesh branches = build_branch_mesh(tree.skeleton, tubes);
    branches.origin = tree.skeleton.origin;
    for (const auto& lobe : tree.lobes) branches.append(lobe);
    return branches;
}

// One template per species: which tree it copies, its size, its index.
struct SpeciesTemplate {
    int index = 0;
    double height = 0, crown_diameter = 0;
};

// "geometry-templates" (templates sorted by species name) and each species' template. The
// template of a species is its tree of median height (the lower middle one for an even count).
json geometry_templates(const std::vector<ExportTree>& trees, const std::vector<TreeMeasures>& measures, const CityJsonOptions& options,
                        std::map<std::string, SpeciesTemplate>& of_species) {
    std::map<std::string, std::vector<std::size_t>> trees_of_species;
    for (std::size_t i = 0; i < trees.size(); ++i) trees_of_species[trees[i].species].push_back(i);
    json templates = json::array();
    VertexGrid grid(Eigen::Vector3d::Zero());
    for (auto& [species, members] : trees_of_species) {
        std::stable_sort(members.begin(), members.end(),
                         [&](std::size_t a, std::size_t b) { return measures[a].height < measures[b].height; });
        const std::size_t chosen = members[(members.size() - 1) / 2];
        TriangleMesh mesh = lod2_mesh(trees[chosen], options);
        mesh.origin -= measures[chosen].base;  // relative to the stem base
        of_species[species] = {static_cast<int>(templates.size()), measures[chosen].height, measures[chosen].crown_diameter};
        templates.push_back({{"type", "MultiSurface"}, {"lod", "2"}, {"boundaries", grid.surfaces(mesh)}});
    }
    return {{"templates", templates}, {"vertices-templates", grid.vertices_in_metres()}};
}

// Scales the template to the tree (row-major 4x4, no rotation; the reference point places it).
json transformation_matrix(const TreeMeasures& tree, const SpeciesTemplate& t) {
    const double across = t.crown_diameter > 0 && tree.crown_diameter > 0 ? tree.crown_diameter / t.crown_diameter : 1.0;
    const double up = t.height > 0 && tree.height > 0 ? tree.height / t.height : 1.0;
    const auto round6 = [](double v) { return std::round(v * 1e6) / 1e6; };
    return {round6(across), 0, 0, 0, 0, round6(across), 0, 0, 0, 0, round6(up), 0, 0, 0, 0, 1};
}

json tree_object(const ExportTree& tree, const TreeMeasures& m, VertexGrid& grid, const CityJsonOptions& options,
                 const SpeciesTemplate* instance_of) {
    json attributes = {{"height", millimetres(m.height)},
                       {"trunkDiameter", millimetres(m.dbh)},
                       {"crownDiameter", millimetres(m.crown_diameter)},
                       {"crownBaseHeight", millimetres(m.crown_base_height)},
                       {"crownVolume", millimetres(m.crown_volume)},
                       {"woodVolume", std::round(m.wood_volume * 1e6) / 1e6},
                       {"skeletonLength", millimetres(m.total_length)},
                       {"branchCount", m.branches},
                       {"lobeCount", m.lobes}};
    if (!tree.species.empty()) attributes["species"] = tree.species;
    if (tree.confidence) attributes["confidence"] = std::round(*tree.confidence * 1e4) / 1e4;
    json geometry = json::array();
    if (!m.crown_hull.faces.empty()) {
        const json shell = grid.surfaces(m.crown_hull);
        geometry.push_back({{"type", "Solid"}, {"lod", "1"}, {"boundaries", json::array({shell})}});
    }
    if (instance_of) {
        geometry.push_back({{"type", "GeometryInstance"},
                            {"template", instance_of->index},
                            {"boundaries", json::array({grid.index(m.base)})},
                            {"transformationMatrix", transformation_matrix(m, *instance_of)}});
    } else if (const TriangleMesh branches = lod2_mesh(tree, options); !branches.faces.empty()) {
        geometry.push_back({{"type", "MultiSurface"}, {"lod", "2"}, {"boundaries", grid.surfaces(branches)}});
    }
    return {{"type", "SolitaryVegetationObject"}, {"attributes", attributes}, {"geometry", geometry}};
}

json extent(const json& vertices, const Eigen::Vector3d& translate) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const auto& v : vertices) {
        const Eigen::Vector3d p = translate + kScale * Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    return {millimetres(lo.x()), millimetres(lo.y()), millimetres(lo.z()), millimetres(hi.x()), millimetres(hi.y()), millimetres(hi.z())};
}

void collect_indices(const json& boundaries, std::vector<long long>& out) {
    if (boundaries.is_number_integer())
        out.push_back(boundaries.get<long long>());
    else if (boundaries.is_array())
        for (const auto& b : boundaries) collect_indices(b, out);
}

template <typename Visit>
void for_each_ring(const json& surfaces, Visit&& visit) {
    for (const auto& surface : surfaces)
        for (const auto& ring : surface) visit(ring);
}

void check_ring(const json& ring, const std::string& where, std::vector<std::string>& problems) {
    std::set<long long> seen;
    for (const auto& v : ring)
        if (!seen.insert(v.get<long long>()).second) problems.push_back(where + ": a ring repeats vertex " + v.dump());
}

// A closed, consistently oriented shell uses every directed edge once and its reverse once.
void check_shell_closed(const json& shell, const std::string& where, std::vector<std::string>& problems) {
    std::map<std::pair<long long, long long>, int> directed;
    for_each_ring(shell, [&](const json& ring) {
        check_ring(ring, where, problems);
        for (std::size_t k = 0; k < ring.size(); ++k) ++directed[{ring[k].get<long long>(), ring[(k + 1) % ring.size()].get<long long>()}];
    });
    for (const auto& [edge, count] : directed) {
        const auto reverse = directed.find({edge.second, edge.first});
        if (count != 1 || reverse == directed.end() || reverse->second != 1) {
            problems.push_back(where + ": shell not closed at edge " + std::to_string(edge.first) + "-" + std::to_string(edge.second));
            return;
        }
    }
}

void check_instance(const json& geometry, const std::string& id, long long vertex_count, long long template_count,
                    std::vector<std::string>& problems) {
    const std::string where = id + " GeometryInstance";
    const json index = geometry.value("template", json());
    if (!index.is_number_integer() || index.get<long long>() < 0 || index.get<long long>() >= template_count)
        problems.push_back(where + ": template " + index.dump() + " not among the " + std::to_string(template_count) + " templates");
    const json reference = geometry.value("boundaries", json::array());
    if (reference.size() != 1 || !reference[0].is_number_integer() || reference[0].get<long long>() < 0 ||
        reference[0].get<long long>() >= vertex_count)
        problems.push_back(where + ": reference point " + reference.dump() + " is not one vertex index in range");
    const json matrix = geometry.value("transformationMatrix", json::array());
    bool affine = matrix.size() == 16;
    for (std::size_t k = 0; affine && k < 16; ++k) affine = matrix[k].is_number() && std::isfinite(matrix[k].get<double>());
    if (affine) affine = matrix[12] == 0 && matrix[13] == 0 && matrix[14] == 0 && matrix[15] == 1;
    if (!affine) problems.push_back(where + ": transformationMatrix is not 16 finite numbers of an affine map");
}

void check_geometry(const json& geometry, const std::string& id, long long vertex_count, std::vector<std::string>& problems) {
    const std::string type = geometry.value("type", "?");
    const std::string where = id + " " + type + " lod " + geometry.value("lod", "?");
    const json boundaries = geometry.value("boundaries", json::array());
    std::vector<long long> indices;
    collect_indices(boundaries, indices);
    for (long long i : indices)
        if (i < 0 || i >= vertex_count) {
            problems.push_back(where + ": vertex index " + std::to_string(i) + " out of range");
            return;
        }
    if (type == "MultiSurface") for_each_ring(boundaries, [&](const json& ring) { check_ring(ring, where, problems); });
    if (type == "Solid")
        for (const auto& shell : boundaries) check_shell_closed(shell, where, problems);
}

}  // namespace

std::string cityjson_text(const std::vector<ExportTree>& trees, const std::string& crs, const CityJsonOptions& options) {
    if (trees.empty()) throw Error::input("", "CityJSON export: no trees");
    const Eigen::Vector3d translate = minimum_corner(trees);
    VertexGrid grid(translate);
    std::vector<TreeMeasures> measures;
    for (const auto& tree : trees) measures.push_back(measure_tree(tree));
    std::map<std::string, SpeciesTemplate> templates;
    json geometry_template_block;
    if (options.instances) geometry_template_block = geometry_templates(trees, measures, options, templates);
    json objects = json::object();
    for (std::size_t i = 0; i < trees.size(); ++i)
        objects[trees[i].name] =
                tree_object(trees[i], measures[i], grid, options, options.instances ? &templates.at(trees[i].species) : nullptr);
    json vertices = grid.vertices();
    json metadata = {{"title", "trees exported by treelobes " + std::string(kVersion)}};
    if (!vertices.empty()) metadata["geographicalExtent"] = extent(vertices, translate);
    if (const std::string code = epsg_code(crs); !code.empty())
        metadata["referenceSystem"] = "https://www.opengis.net/def/crs/EPSG/0/" + code;
    json document = {{"type", "CityJSON"},
                     {"version", "2.0"},
                     {"transform", {{"scale", {kScale, kScale, kScale}}, {"translate", {translate.x(), translate.y(), translate.z()}}}},
                     {"metadata", metadata},
                     {"CityObjects", objects},
                     {"vertices", vertices}};
    if (options.instances) document["geometry-templates"] = geometry_template_block;
    return document.dump() + "\n";
}

std::vector<std::string> check_cityjson(const std::string& text) {
    json document;
    try {
        document = json::parse(text);
    } catch (const json::exception& e) {
        throw Error::input("", std::string("not JSON: ") + e.what());
    }
    std::vector<std::string> problems;
    const long long vertex_count = static_cast<long long>(document.value("vertices", json::array()).size());
    const json objects = document.value("CityObjects", json::object());
    const json templates = document.value("geometry-templates", json::object());
    const long long template_count = static_cast<long long>(templates.value("templates", json::array()).size());
    const long long template_vertex_count = static_cast<long long>(templates.value("vertices-templates", json::array()).size());
    for (const auto& [id, object] : objects.items()) {
        const json geometries = object.value("geometry", json::array());
        for (const auto& geometry : geometries) {
            if (geometry.value("type", "") == "GeometryInstance")
                check_instance(geometry, id, vertex_count, template_count, problems);
            else
                check_geometry(geometry, id, vertex_count, problems);
        }
    }
    for (long long t = 0; t < template_count; ++t)
        check_geometry(templates["templates"][t], "template " + std::to_string(t), template_vertex_count, problems);
    return problems;
}

}  // namespace treelobes::exporting
