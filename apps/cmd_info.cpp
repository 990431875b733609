// `treelobes info FILE...`: format, version, counts, bounds, attributes and CRS of point
// clouds, meshes and skeletons, and what treelobes' own files hold (apps/product_file_info.hpp).
// Every file is reported; the exit code is 2 if any failed.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/product_file_info.hpp"
#include "core/error.hpp"
#include "core/file_info.hpp"
#include "core/version.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

namespace treelobes::cli {

namespace {

struct InfoOptions {
    std::vector<std::string> files;
    std::string bounds;  // --bounds: describe only the points inside this box
};

std::string chunk_size_text(std::uint32_t chunk_size) { return chunk_size == 0xFFFFFFFFu ? "variable" : std::to_string(chunk_size); }

nlohmann::json to_json(const FileInfo& info) {
    nlohmann::json j = {{"path", info.path},
                        {"kind", info.kind},
                        {"format", info.format},
                        {"points", info.point_count},
                        {"bounds",
                         {{"min", {info.bounds_min.x(), info.bounds_min.y(), info.bounds_min.z()}},
                          {"max", {info.bounds_max.x(), info.bounds_max.y(), info.bounds_max.z()}}}}};
    if (!info.version.empty()) j["version"] = info.version;
    if (info.las_point_format >= 0) {
        j["point_format"] = info.las_point_format;
        j["scale"] = {info.las_scale.x(), info.las_scale.y(), info.las_scale.z()};
        j["offset"] = {info.las_offset.x(), info.las_offset.y(), info.las_offset.z()};
    }
    if (info.kind == "mesh" || info.kind == "city model") j["faces"] = info.face_count;
    if (info.kind == "qsm") {
        j["cylinders"] = info.object_count;
        j["total_length"] = info.total_length;
        j["volume"] = info.volume;
    }
    if (info.format == "glb") j["nodes"] = info.object_count;
    if (info.kind == "city model") j["city_objects"] = info.object_count;
    if (info.kind == "skeleton") {
        j["tips"] = info.tip_count;
        j["total_length"] = info.total_length;
    }
    if (info.dropped_non_finite) j["dropped_non_finite"] = info.dropped_non_finite;
    if (info.format == "laz") {
        j["laz"] = {{"point_format", info.las_point_format}, {"chunks", info.laz_chunks}};
        if (info.laz_chunk_size == 0xFFFFFFFFu)
            j["laz"]["chunk_size"] = "variable";
        else
            j["laz"]["chunk_size"] = info.laz_chunk_size;
    }
    if (info.copc_levels >= 0) j["copc"] = {{"levels", info.copc_levels}, {"nodes", info.copc_nodes}, {"nodes_read", info.copc_nodes_read}};
    if (info.bounds_query) j["bounds_query"] = true;
    j["attributes"] = nlohmann::json::array();
    for (const auto& [name, type] : info.attributes) j["attributes"].push_back({{"name", name}, {"type", type}});
    j["crs"] = info.crs;
    return j;
}

void print_human(const FileInfo& info) {
    std::cout << info.path << "\n";
    std::cout << "  " << info.kind << ", " << info.format;
    if (!info.version.empty()) std::cout << " " << info.version;
    if (info.las_point_format >= 0) std::cout << ", point format " << info.las_point_format;
    std::cout << "\n";
    if (info.format == "laz")
        std::cout << "  LAZ (point format " << info.las_point_format << ", chunk size " << chunk_size_text(info.laz_chunk_size) << "), "
                  << info.laz_chunks << (info.laz_chunks == 1 ? " chunk" : " chunks") << "\n";
    if (info.copc_levels >= 0) {
        std::cout << "  COPC octree: " << info.copc_levels << " levels, " << info.copc_nodes << " nodes";
        if (info.bounds_query) std::cout << " (" << info.copc_nodes_read << " read for --bounds)";
        std::cout << "\n";
    }
    const char* noun = info.kind == "point cloud" ? "points" : info.kind == "skeleton" ? "nodes" : "vertices";
    if (info.kind == "qsm")
        std::cout << "  " << info.object_count << " cylinders, total length " << info.total_length << " m, volume " << info.volume << " m3";
    else
        std::cout << "  " << info.point_count << " " << noun << (info.bounds_query ? " inside --bounds" : "");
    if (info.kind == "mesh" || info.kind == "city model") std::cout << ", " << info.face_count << " faces";
    if (info.format == "glb") std::cout << ", " << info.object_count << " scene nodes";
    if (info.kind == "city model") std::cout << ", " << info.object_count << " city objects";
    if (info.kind == "skeleton") std::cout << ", " << info.tip_count << " tips, total length " << info.total_length << " m";
    if (info.dropped_non_finite) std::cout << " (" << info.dropped_non_finite << " NaN/inf points dropped)";
    std::cout << "\n";
    char line[256];
    std::snprintf(line, sizeof line, "  bounds x %.3f .. %.3f, y %.3f .. %.3f, z %.3f .. %.3f\n", info.bounds_min.x(), info.bounds_max.x(),
                  info.bounds_min.y(), info.bounds_max.y(), info.bounds_min.z(), info.bounds_max.z());
    std::cout << line;
    if (!info.attributes.empty()) {
        std::cout << "  attributes:";
        for (const auto& [name, type] : info.attributes) std::cout << " " << name << " (" << type << ")";
        std::cout << "\n";
    }
    if (!info.crs.empty()) std::cout << "  crs: " << info.crs.substr(0, 120) << (info.crs.size() > 120 ? "..." : "") << "\n";
}

int run_info(const InfoOptions& options, const OptionTable& table, const GlobalOptions& global) {
    nlohmann::json files = nlohmann::json::array();
    int exit_code = 0;
    std::optional<Box3d> bounds;
    if (!options.bounds.empty()) bounds = parse_bounds(options.bounds);
    for (const auto& file : options.files) {
        try {
            if (is_product_file(file)) {
                if (bounds) throw Error::usage("--bounds applies to point clouds, not to " + file);
                const nlohmann::json info = describe_product_file(file);
                if (global.json)
                    files.push_back(info);
                else
                    print_product_file(info);
                continue;
            }
            const FileInfo info = describe_file(file, bounds);
            if (global.json)
                files.push_back(to_json(info));
            else
                print_human(info);
        } catch (const Error& e) {
            std::cerr << "treelobes: error: " << e.what() << "\n";
            if (global.json) files.push_back({{"path", file}, {"error", e.what()}});
            exit_code = static_cast<int>(e.code());
        }
    }
    if (global.json) std::cout << nlohmann::json{{"treelobes", kVersion}, {"options", table.json()}, {"files", files}}.dump(2) << "\n";
    return exit_code;
}

}  // namespace

void add_info_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<InfoOptions>();
    CLI::App* sub = app.add_subcommand(
            "info",
            "Describe point clouds (LAS, LAZ, COPC, PLY, PCD, XYZ/CSV), meshes (PLY, OBJ, OFF, glb), skeletons, QSMs, CityJSON and "
            "treelobes' own .dbf6 trees, .forest files and .tlobe lobe trees");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("files", options->files, "Files to describe")->required();
    table->add("--bounds", options->bounds,
               "Describe only the points inside minx,miny,minz,maxx,maxy,maxz (or minx,miny,maxx,maxy); "
               "COPC files read only the octree nodes that meet the box");
    sub->callback([options, table, &global, &job] { job = [options, table, &global] { return run_info(*options, *table, global); }; });
}

}  // namespace treelobes::cli
