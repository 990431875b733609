#include "core/file_info.hpp"

#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/mesh_io.hpp"
#include "core/ply_format.hpp"
#include "core/skeleton_io.hpp"

#include <cmath>
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
    if (info.crs.empty() && !cloud.georef.las_vlrs.empty()) info.crs = "GeoTIFF keys (" + std::to_string(cloud.georef.las_vlrs.size()) + " VLRs)";
    return info;
}

FileInfo describe_mesh(const fs::path& path) {
    const TriangleMesh mesh = read_mesh(path);
    FileInfo info;
    info.kind = "mesh";
    info.format = file_extension(path);
    info.point_count = mesh.vertex_count();
    info.face_count = mesh.face_count();
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

}  // namespace

FileInfo describe_file(const fs::path& path, const std::optional<Box3d>& bounds) {
    const std::string ext = file_extension(path);
    FileInfo info;
    if (ext == "obj" || ext == "off" || ext == "stl") info = describe_mesh(path);
    else if (ext == "ply" && fs::is_regular_file(path)) {
        const std::string kind = ply_kind(path);
        info = kind == "mesh" ? describe_mesh(path) : kind == "skeleton" ? describe_skeleton(path) : describe_cloud(path, bounds);
    } else info = describe_cloud(path, bounds);
    info.path = path.string();
    return info;
}

}  // namespace treelobes
