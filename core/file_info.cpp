#include "core/file_info.hpp"

#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/mesh_io.hpp"
#include "core/georef_sidecar.hpp"
#include "core/glb_container.hpp"
#include "core/ply_format.hpp"
#include "core/qsm_io.hpp"
#include "core/atomic_file.hpp"
#include "core/skeleton_io.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <limits>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

// A PLY holds a skeleton when it has an edge element, a mesh when it has faces.
std::string ply_kind(const fs::path& path) {
    const ply::File file = ply::read(path);
    if (const auto* face = file.find("face"); face && face->count > 0) return "mesh";
    if (const auto* edge = file.find("edge"); edge && edge->count > 0) return "skeleton";
    return "point cloud";
}

template <typename Points>
void set_bounds(FileInfo& info, const Points& points, const Eigen::Vector3d& origin) {
    if (points.empty()) return;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const auto& p : points) {
        const Eigen::Vector3d q = origin + p.template cast<double>();
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    }
    info.bounds_min = lo;
    info.bounds_max = hi;
}

// LAS coordinates are integers times the scale: report the bounds on that grid, as the header
// does, rather than the float round-off of the local frame.
void snap_to_las_grid(FileInfo& info) {
    for (int k = 0; k < 3; ++k) {
        const double scale = info.las_scale[k], offset = info.las_offset[k];
        if (!(scale > 0)) continue;
        info.bounds_min[k] = offset + std::round((info.bounds_min[k] - offset) / scale) * scale;
        info.bounds_max[k] = offset + std::round((info.bounds_max[k] - offset) / scale) * scale;
    }
}

FileInfo describe_cloud(const fs::path& path, const std::optional<Box3d>& bounds) {
    CloudReadOptions options;
    options.bounds = bounds;
    const PointCloud cloud = read_point_cloud(path, options);
    FileInfo info;
    info.kind = "point cloud";
    info.format = cloud.source.format;
    info.bounds_query = bounds.has_value();
    info.laz_chunk_size = cloud.source.laz_chunk_size;
    info.laz_chunks = cloud.source.laz_chunks;
    info.copc_levels = cloud.source.copc_levels;
    info.copc_nodes = cloud.source.copc_nodes;
    info.copc_nodes_read = cloud.source.copc_nodes_read;
    info.version = cloud.source.version;
    info.las_point_format = cloud.source.las_point_format;
    if (info.format == "las") {
        info.las_scale = cloud.source.las_scale;
        info.las_offset = cloud.source.las_offset;
    }
    info.point_count = cloud.size();
    info.dropped_non_finite = cloud.source.dropped_non_finite;
    set_bounds(info, cloud.positions, cloud.origin);
    auto add = [&](const std::string& name, const std::string& type) { info.attributes.emplace_back(name, type); };
    if (!cloud.intensity.empty()) add("intensity", "uint16");
    if (!cloud.return_number.empty()) add("return_number", "uint8");
    if (!cloud.number_of_returns.empty()) add("number_of_returns", "uint8");
    if (!cloud.classification.empty()) add("classification", "uint8");
    if (!cloud.rgb.empty()) add("rgb", "uint16[3]");
    if (!cloud.gps_time.empty()) add("gps_time", "float64");
    for (const auto& extra : cloud.extras) add(extra.name, attribute_type_name(extra.type));
    if (info.format == "las") snap_to_las_grid(info);
    if (cloud.source.laz) info.format = "laz";
    info.crs = cloud.georef.crs_wkt;
    if (info.crs.empty() && !cloud.georef.las_vlrs.empty())
        info.crs = "GeoTIFF keys (" + std::to_string(cloud.georef.las_vlrs.size()) + " VLRs)";
    return info;
}

// Meshes in a local frame (OBJ, OFF, our exports) take the origin and CRS of their georef sidecar.
FileInfo describe_mesh(const fs::path& path) {
    TriangleMesh mesh = read_mesh(path);
    std::string crs;
    if (const auto sidecar = read_georef_sidecar(path)) {
        if (mesh.origin.isZero()) mesh.origin = sidecar->origin;
        crs = sidecar->crs_wkt;
    }
    FileInfo info;
    info.kind = "mesh";
    info.format = file_extension(path);
    info.point_count = mesh.vertex_count();
    info.face_count = mesh.face_count();
    info.crs = crs;
    set_bounds(info, mesh.vertices, mesh.origin);
    return info;
}

FileInfo describe_skeleton(const fs::path& path) {
    const TreeGraph tree = read_skeleton_ply(path);
    FileInfo info;
    info.kind = "skeleton";
    info.format = "ply";
    info.point_count = tree.size();
    info.tip_count = tree.tip_count();
    info.total_length = tree.total_length();
    std::vector<Eigen::Vector3f> positions;
    for (const auto& node : tree.nodes) positions.push_back(node.position);
    set_bounds(info, positions, tree.origin);
    info.attributes.emplace_back("radius", "float32");
    return info;
}

FileInfo describe_qsm(const fs::path& path) {
    const QsmModel model = read_qsm(path);
    FileInfo info;
    info.kind = "qsm";
    info.format = model.format;
    info.object_count = model.cylinders.size();
    info.total_length = model.total_length();
    info.volume = model.volume();
    info.bounds_min = info.bounds_max = model.cylinders.front().start;
    for (const auto& c : model.cylinders)
        for (const Eigen::Vector3d& p : {c.start, c.end()}) {
            info.bounds_min = info.bounds_min.cwiseMin(p);
            info.bounds_max = info.bounds_max.cwiseMax(p);
        }
    info.attributes = {{"radius", "float64"}, {"parent", "int"}, {"branch", "int"}, {"branch_order", "int"}};
    return info;
}

// Counts and bounds of what the default scene shows (LOD 0), back in our z-up frame, plus the
// origin of the georef sidecar.
FileInfo describe_glb(const fs::path& path) {
    const nlohmann::json doc = parse_glb_json(read_glb_container(path), path.string());
    FileInfo info;
    info.kind = "mesh";
    info.format = "glb";
    try {
        info.version = doc.at("asset").at("version").get<std::string>();
        const auto& scene = doc.at("scenes").at(doc.value("scene", 0));
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
        for (const auto& node_index : scene.value("nodes", nlohmann::json::array())) {
            const auto& node = doc.at("nodes").at(node_index.get<std::size_t>());
            ++info.object_count;
            if (!node.contains("mesh")) continue;
            Eigen::Vector3d shift = Eigen::Vector3d::Zero();
            if (node.contains("translation"))
                shift = {node["translation"][0].get<double>(), node["translation"][1].get<double>(), node["translation"][2].get<double>()};
            for (const auto& primitive : doc.at("meshes").at(node.at("mesh").get<std::size_t>()).at("primitives")) {
                const auto& position = doc.at("accessors").at(primitive.at("attributes").at("POSITION").get<std::size_t>());
                info.point_count += position.at("count").get<std::size_t>();
                if (primitive.contains("indices"))
                    info.face_count += doc.at("accessors").at(primitive["indices"].get<std::size_t>()).at("count").get<std::size_t>() / 3;
                for (int k = 0; k < 3; ++k) {
                    lo[k] = std::min(lo[k], shift[k] + position.at("min").at(k).get<double>());
                    hi[k] = std::max(hi[k], shift[k] + position.at("max").at(k).get<double>());
                }
            }
        }
        if (info.point_count > 0) {  // y-up (x, y, z) is our (x, -z, y)
            info.bounds_min = {lo.x(), -hi.z(), lo.y()};
            info.bounds_max = {hi.x(), -lo.z(), hi.y()};
        }
    } catch (const nlohmann::json::exception& e) {
        throw Error::input(path.string(), std::string("glTF JSON lacks what a scene needs: ") + e.what());
    }
    if (const auto sidecar = read_georef_sidecar(path)) {
        info.bounds_min += sidecar->origin;
        info.bounds_max += sidecar->origin;
        info.crs = sidecar->crs_wkt;
    }
    return info;
}

// A surface is an array of rings and a ring an array of vertex indices.
void count_surfaces(const nlohmann::json& boundaries, std::size_t& surfaces) {
    if (!boundaries.is_array() || boundaries.empty()) return;
    if (boundaries[0].is_array() && !boundaries[0].empty() && boundaries[0][0].is_number()) {
        ++surfaces;
        return;
    }
    for (const auto& b : boundaries) count_surfaces(b, surfaces);
}

FileInfo describe_cityjson(const fs::path& path) {
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(read_file(path));
    } catch (const nlohmann::json::exception& e) {
        throw Error::input(path.string(), std::string("not JSON: ") + e.what());
    }
    FileInfo info;
    info.kind = "city model";
    info.format = "cityjson";
    try {
        info.version = doc.at("version").get<std::string>();
        const auto& scale = doc.at("transform").at("scale");
        const auto& translate = doc.at("transform").at("translate");
        const auto& vertices = doc.at("vertices");
        info.point_count = vertices.size();
        for (std::size_t i = 0; i < vertices.size(); ++i)
            for (int k = 0; k < 3; ++k) {
                const double v = translate.at(k).get<double>() + scale.at(k).get<double>() * vertices[i].at(k).get<double>();
                info.bounds_min[k] = i == 0 ? v : std::min(info.bounds_min[k], v);
                info.bounds_max[k] = i == 0 ? v : std::max(info.bounds_max[k], v);
            }
        for (const auto& [id, object] : doc.at("CityObjects").items()) {
            ++info.object_count;
            for (const auto& geometry : object.value("geometry", nlohmann::json::array()))
                count_surfaces(geometry.value("boundaries", nlohmann::json::array()), info.face_count);
        }
        if (doc.contains("metadata")) info.crs = doc["metadata"].value("referenceSystem", "");
    } catch (const nlohmann::json::exception& e) {
        throw Error::input(path.string(), std::string("CityJSON lacks ") + e.what());
    }
    return info;
}

bool is_cityjson(const fs::path& path) {
    const std::string name = path.filename().string();
    return file_extension(path) == "json" && name.find(".georef.json") == std::string::npos;
}

// QSMs: a SimpleForest/rTwig header, or TreeQSM's 15 columns (fewer could be an XYZ cloud with
// colours and normals).
bool is_qsm_text(const fs::path& path) {
    const std::string ext = file_extension(path);
    if ((ext != "txt" && ext != "csv") || !fs::is_regular_file(path)) return false;
    std::size_t columns = 0;
    const QsmFileKind kind = detect_qsm_file(path, &columns);
    return kind == QsmFileKind::Csv || (kind == QsmFileKind::TreeQsm && columns == 15);
}

}  // namespace

FileInfo describe_file(const fs::path& path, const std::optional<Box3d>& bounds) {
    const std::string ext = file_extension(path);
    FileInfo info;
    if (ext == "obj" || ext == "off" || ext == "stl")
        info = describe_mesh(path);
    else if (ext == "glb")
        info = describe_glb(path);
    else if (is_cityjson(path))
        info = describe_cityjson(path);
    else if (is_qsm_text(path))
        info = describe_qsm(path);
    else if (ext == "ply" && fs::is_regular_file(path)) {
        const std::string kind = ply_kind(path);
        info = kind == "mesh" ? describe_mesh(path) : kind == "skeleton" ? describe_skeleton(path) : describe_cloud(path, bounds);
    } else
        info = describe_cloud(path, bounds);
    info.path = path.string();
    return info;
}

}  // namespace treelobes
