#include "apps/product_file_info.hpp"

#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/tree_graph.hpp"
#include "encode/chain_code.hpp"
#include "encode/coder.hpp"
#include "encode/forest_file.hpp"
#include "encode/tree_file.hpp"
#include "lobes/lobe_tree.hpp"
#include "lobes/tlobe_io.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace treelobes::cli {

namespace fs = std::filesystem;

namespace {

// Running bounds of world points, as the JSON {"min": [...], "max": [...]}.
class Bounds {
public:
    void add(const Eigen::Vector3d& p) {
        lo_ = lo_.cwiseMin(p);
        hi_ = hi_.cwiseMax(p);
    }
    void add_local(const Eigen::Vector3d& origin, const Eigen::Vector3f& p) { add(origin + p.cast<double>()); }
    nlohmann::json json() const {
        if (lo_.x() > hi_.x()) return nullptr;
        return {{"min", {lo_.x(), lo_.y(), lo_.z()}}, {"max", {hi_.x(), hi_.y(), hi_.z()}}};
    }

private:
    Eigen::Vector3d lo_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi_ = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
};

nlohmann::json common(const fs::path& path, const char* kind, const char* format) {
    std::error_code ec;
    const auto bytes = fs::file_size(path, ec);
    return {{"path", path.string()}, {"kind", kind}, {"format", format}, {"bytes", ec ? 0 : bytes}};
}

nlohmann::json skeleton_json(const TreeGraph& tree) {
    Bounds bounds;
    for (const auto& node : tree.nodes) bounds.add_local(tree.origin, node.position);
    return {{"nodes", tree.size()}, {"tips", tree.tip_count()}, {"total_length", tree.total_length()}, {"bounds", bounds.json()}};
}

// One line per level: the internodes it keeps, the thinnest lateral kept (Strnad et al. 2020,
// Pseudocode 2's threshold) and its two compressed streams.
nlohmann::json lods_json(const encode::StoredTree& tree, const std::vector<encode::StreamSizes>& sizes) {
    nlohmann::json lods = nlohmann::json::array();
    for (std::size_t k = 0; k < sizes.size(); ++k) {
        nlohmann::json lod = {{"level", k},
                              {"internodes", sizes[k].internodes},
                              {"symbols", sizes[k].code_length},
                              {"symbol_bytes", sizes[k].symbols},
                              {"radius_bytes", sizes[k].radii}};
        if (k > 0 && k - 1 < tree.thresholds.size()) lod["threshold_m"] = tree.thresholds[k - 1] * tree.radius_unit;
        lods.push_back(lod);
    }
    return lods;
}

nlohmann::json describe_dbf6(const fs::path& path) {
    std::vector<encode::StreamSizes> sizes;
    const encode::StoredTree stored = encode::read_tree_file(path, -1, &sizes);
    nlohmann::json j = common(path, "tree", "dbf6");
    j["version"] = encode::kTreeFileVersion;
    j["code"] = encode::code_kind_name(stored.kind);
    j["coder"] = encode::coder_name(stored.coder);
    j["resolution"] = stored.resolution;
    j["internode_length"] = stored.internode_length;
    j["lods"] = lods_json(stored, sizes);
    j["skeleton"] = skeleton_json(encode::decode_stored_tree(stored, 0, path.string()));
    return j;
}

nlohmann::json describe_forest(const fs::path& path) {
    encode::ForestReader reader(path);
    nlohmann::json j = common(path, "forest", "forest");
    j["version"] = encode::kForestFileVersion;
    j["index_bytes"] = reader.index_bytes();
    Bounds positions;
    nlohmann::json trees = nlohmann::json::array();
    for (std::size_t i = 0; i < reader.size(); ++i) {
        const encode::ForestEntry& e = reader.entry(i);
        positions.add(e.position);
        trees.push_back({{"name", e.name},
                         {"position", {e.position.x(), e.position.y(), e.position.z()}},
                         {"azimuth_deg", e.azimuth * 180.0 / std::numbers::pi},
                         {"bytes", e.size}});
    }
    j["tree_positions"] = positions.json();
    if (reader.size() > 0) {  // the LODs every tree was written with, read from the first
        std::vector<encode::StreamSizes> sizes;
        const encode::StoredTree first = reader.read(0, -1, &sizes);
        j["coder"] = encode::coder_name(first.coder);
        j["lods_per_tree"] = first.lods.size();
    }
    j["trees"] = trees;
    return j;
}

nlohmann::json describe_tlobe(const fs::path& path) {
    const lobes::LobeTree tree = lobes::read_tlobe(path);
    const std::string header = read_file(path).substr(0, 6);  // magic, major, minor (docs/tlobe.md)
    nlohmann::json j = common(path, "lobe tree", "tlobe");
    j["version"] = std::to_string(static_cast<unsigned char>(header[4])) + "." + std::to_string(static_cast<unsigned char>(header[5]));
    j["species"] = tree.species.empty() ? nlohmann::json() : nlohmann::json(tree.species);
    j["parameters"] = {{"beta", tree.beta}, {"gamma", tree.gamma}, {"fs", tree.fs}, {"alpha_factor", tree.alpha_factor}};
    j["root_diameter"] = tree.root_diameter;
    j["leaf_area_m2"] = tree.leaf_area_m2 > 0 ? nlohmann::json(tree.leaf_area_m2) : nlohmann::json();
    j["main_skeleton"] = skeleton_json(tree.skeleton);
    std::size_t faces = 0, vertices = 0, with_occupancy = 0, occupied_cells = 0, derived = 0;
    float finest = 0, coarsest = 0;
    Bounds bounds;
    for (const auto& node : tree.skeleton.nodes) bounds.add_local(tree.skeleton.origin, node.position);
    for (const auto& lobe : tree.lobes) {
        faces += lobe.mesh.faces.size();
        vertices += lobe.mesh.vertices.size();
        for (const auto& v : lobe.mesh.vertices) bounds.add_local(tree.skeleton.origin, v);
        if (lobe.surface_from_occupancy) ++derived;
        if (lobe.occupancy.empty()) continue;
        ++with_occupancy;
        occupied_cells += lobe.occupancy.occupied_count();
        finest = finest == 0 ? lobe.occupancy.cell : std::min(finest, lobe.occupancy.cell);
        coarsest = std::max(coarsest, lobe.occupancy.cell);
    }
    j["lobes"] = {{"count", tree.lobes.size()},
                  {"faces", faces},
                  {"vertices", vertices},
                  {"with_occupancy", with_occupancy},
                  {"occupied_cells", occupied_cells},
                  {"surfaces_from_occupancy", derived}};
    if (with_occupancy > 0) j["lobes"]["occupancy_cell_m"] = {finest, coarsest};
    j["bounds"] = bounds.json();
    return j;
}

// "1 tip", "2 tips".
std::string counted(std::size_t n, const char* noun) { return std::to_string(n) + " " + noun + (n == 1 ? "" : "s"); }

void print_bounds(const char* label, const nlohmann::json& b) {
    if (b.is_null()) return;
    std::printf("  %s x %.3f .. %.3f, y %.3f .. %.3f, z %.3f .. %.3f\n", label, b["min"][0].get<double>(), b["max"][0].get<double>(),
                b["min"][1].get<double>(), b["max"][1].get<double>(), b["min"][2].get<double>(), b["max"][2].get<double>());
}

void print_skeleton(const char* label, const nlohmann::json& s) {
    std::printf("  %s: %s, %s, total length %.2f m\n", label, counted(s["nodes"], "node").c_str(), counted(s["tips"], "tip").c_str(),
                s["total_length"].get<double>());
    print_bounds("bounds", s["bounds"]);
}

void print_dbf6(const nlohmann::json& j) {
    std::printf("  %s chain code, coder %s, resolution %g, internode %.4f m; %zu bytes\n", j["code"].get<std::string>().c_str(),
                j["coder"].get<std::string>().c_str(), j["resolution"].get<double>(), j["internode_length"].get<double>(),
                j["bytes"].get<std::size_t>());
    for (const auto& lod : j["lods"]) {
        std::printf("  LOD %zu: %zu internodes, %zu symbols -> %zu + %zu bytes (symbols + radii)", lod["level"].get<std::size_t>(),
                    lod["internodes"].get<std::size_t>(), lod["symbols"].get<std::size_t>(), lod["symbol_bytes"].get<std::size_t>(),
                    lod["radius_bytes"].get<std::size_t>());
        if (lod.contains("threshold_m")) std::printf(", laterals under %.4f m radius pruned", lod["threshold_m"].get<double>());
        std::printf("\n");
    }
    print_skeleton("skeleton (LOD 0)", j["skeleton"]);
}

void print_forest(const nlohmann::json& j) {
    const auto& trees = j["trees"];
    std::printf("  %s in %zu bytes (index %zu bytes)", counted(trees.size(), "tree").c_str(), j["bytes"].get<std::size_t>(),
                j["index_bytes"].get<std::size_t>());
    if (j.contains("lods_per_tree"))
        std::printf(", coder %s, %s per tree", j["coder"].get<std::string>().c_str(), counted(j["lods_per_tree"], "LOD").c_str());
    std::printf("\n");
    print_bounds("tree positions", j["tree_positions"]);
    constexpr std::size_t kListed = 10;
    for (std::size_t i = 0; i < std::min(kListed, trees.size()); ++i) {
        const auto& t = trees[i];
        std::printf("  %4zu %-24s %12.3f %12.3f %9.3f  %6zu bytes\n", i, t["name"].get<std::string>().c_str(),
                    t["position"][0].get<double>(), t["position"][1].get<double>(), t["position"][2].get<double>(),
                    t["bytes"].get<std::size_t>());
    }
    if (trees.size() > kListed) std::printf("  ... %zu more (info --json lists every tree)\n", trees.size() - kListed);
}

void print_tlobe(const nlohmann::json& j) {
    const auto& lobes = j["lobes"];
    std::printf("  species %s, %zu bytes\n", j["species"].is_null() ? "(none)" : j["species"].get<std::string>().c_str(),
                j["bytes"].get<std::size_t>());
    std::printf("  %s: %zu faces, %zu vertices", counted(lobes["count"], "lobe").c_str(), lobes["faces"].get<std::size_t>(),
                lobes["vertices"].get<std::size_t>());
    if (lobes.contains("occupancy_cell_m"))
        std::printf("; occupancy in %zu, %zu cells of %.3f .. %.3f m", lobes["with_occupancy"].get<std::size_t>(),
                    lobes["occupied_cells"].get<std::size_t>(), lobes["occupancy_cell_m"][0].get<double>(),
                    lobes["occupancy_cell_m"][1].get<double>());
    if (const auto derived = lobes["surfaces_from_occupancy"].get<std::size_t>(); derived > 0)
        std::printf("; %zu surfaces derived from the occupancy", derived);
    std::printf("\n");
    std::printf("  root diameter %.3f m", j["root_diameter"].get<double>());
    if (!j["leaf_area_m2"].is_null()) std::printf(", leaf area %.1f m^2", j["leaf_area_m2"].get<double>());
    std::printf("\n");
    const auto& skeleton = j["main_skeleton"];
    std::printf("  main skeleton: %s, %s, total length %.2f m\n", counted(skeleton["nodes"], "node").c_str(),
                counted(skeleton["tips"], "tip").c_str(), skeleton["total_length"].get<double>());
    print_bounds("bounds", j["bounds"]);
}

}  // namespace

bool is_product_file(const fs::path& path) {
    const std::string ext = file_extension(path);
    return ext == "dbf6" || ext == "forest" || ext == "tlobe";
}

nlohmann::json describe_product_file(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw Error::input(path.string(), "no such file");
    const std::string ext = file_extension(path);
    if (ext == "dbf6") return describe_dbf6(path);
    if (ext == "forest") return describe_forest(path);
    return describe_tlobe(path);
}

void print_product_file(const nlohmann::json& info) {
    const std::string version =
            info["version"].is_string() ? info["version"].get<std::string>() : std::to_string(info["version"].get<int>());
    std::printf("%s\n  %s, .%s version %s\n", info["path"].get<std::string>().c_str(), info["kind"].get<std::string>().c_str(),
                info["format"].get<std::string>().c_str(), version.c_str());
    const std::string format = info["format"];
    if (format == "dbf6")
        print_dbf6(info);
    else if (format == "forest")
        print_forest(info);
    else
        print_tlobe(info);
}

}  // namespace treelobes::cli
