#include "export/tree_input.hpp"

#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/ply_format.hpp"
#include "core/skeleton_io.hpp"
#include "encode/forest_file.hpp"
#include "encode/tree_file.hpp"
#include "lobes/tlobe_io.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <set>

namespace fs = std::filesystem;

namespace treelobes::exporting {

namespace {

bool is_skeleton_ply(const fs::path& path) {
    const ply::File file = ply::read(path);
    const ply::Element* edge = file.find("edge");
    const ply::Element* face = file.find("face");
    return edge && edge->count > 0 && !(face && face->count > 0);
}

ExportTree tree_from_tlobe(const fs::path& path) {
    lobes::LobeTree lobe_tree = lobes::read_tlobe(path);
    ExportTree tree;
    tree.name = path.stem().string();
    tree.skeleton = std::move(lobe_tree.skeleton);
    tree.species = lobe_tree.species;
    std::size_t lobe_points = 0;
    for (const auto& lobe : lobe_tree.lobes) lobe_points += lobe.points;
    tree.confidence = tree_confidence(path, lobe_points);
    for (auto& lobe : lobe_tree.lobes) {
        lobe.mesh.origin = tree.skeleton.origin;  // decoded lobes are in the skeleton's frame
        tree.lobes.push_back(std::move(lobe.mesh));
    }
    return tree;
}

void read_file_into(const fs::path& path, int lod, ExportInput& input) {
    const std::string ext = file_extension(path);
    if (ext == "forest") {
        encode::ForestReader forest(path);
        for (std::size_t i = 0; i < forest.size(); ++i) {
            ExportTree tree;
            tree.name = forest.entry(i).name.empty() ? path.stem().string() + "_" + std::to_string(i) : forest.entry(i).name;
            tree.skeleton = forest.decode(i, lod);
            input.trees.push_back(std::move(tree));
        }
    } else {
        ExportTree tree;
        if (ext == "tlobe")
            tree = tree_from_tlobe(path);
        else if (ext == "dbf6") {
            tree.name = path.stem().string();
            tree.skeleton = encode::decode_stored_tree(encode::read_tree_file(path, lod), lod, path.string());
        } else if (ext == "ply") {
            tree.name = path.stem().string();
            tree.skeleton = read_skeleton_ply(path);
        } else
            throw Error::input(path.string(), "not a tree file: expected a skeleton PLY, .tlobe, .dbf6, .forest or a folder of them");
        tree.skeleton.validate(path.string());
        input.trees.push_back(std::move(tree));
    }
    if (input.crs.empty())
        if (const auto sidecar = read_georef_sidecar(path)) input.crs = sidecar->crs_wkt;
    input.files.push_back(path.string());
}

// Several files may hold trees of the same name (tile folders): later ones get "_2", "_3", ...
void make_names_unique(std::vector<ExportTree>& trees) {
    std::set<std::string> used;
    for (auto& tree : trees) {
        std::string name = tree.name;
        for (int k = 2; used.contains(name); ++k) name = tree.name + "_" + std::to_string(k);
        tree.name = name;
        used.insert(name);
    }
}

}  // namespace

std::optional<double> tree_confidence(const fs::path& tlobe, std::size_t lobe_points) {
    const fs::path dir = tlobe.parent_path(), stem = tlobe.stem();
    double tree_points = 0;
    for (const fs::path& record : {dir / (stem.string() + ".json"), dir / (stem.string() + "_lobes.json")}) {
        if (!fs::is_regular_file(record)) continue;
        nlohmann::json json;
        try {
            json = nlohmann::json::parse(read_file(record));
        } catch (const nlohmann::json::exception& e) {
            throw Error::input(record.string(), std::string("not JSON: ") + e.what());
        }
        const nlohmann::json points = json.value("points", nlohmann::json());
        if (points.is_number())
            tree_points = points.get<double>();  // tile record: all points of the tree
        else if (points.is_object() && points.value("main", nlohmann::json()).is_number() &&
                 points.value("lobes", nlohmann::json()).is_number())
            tree_points = points["main"].get<double>() + points["lobes"].get<double>();  // lobes summary
        if (tree_points > 0) break;
    }
    if (!(tree_points > 0)) return std::nullopt;
    return std::clamp(1.0 - static_cast<double>(lobe_points) / tree_points, 0.0, 1.0);
}

bool is_tree_file(const fs::path& path) {
    const std::string ext = file_extension(path);
    if (ext == "tlobe" || ext == "dbf6" || ext == "forest") return true;
    if (ext != "ply") return false;
    try {
        return is_skeleton_ply(path);
    } catch (const Error&) {
        return false;  // an unreadable PLY in a folder is not one of our trees
    }
}

ExportInput read_export_input(const fs::path& path, int lod) {
    if (lod < 0) throw Error::usage("the LOD must be >= 0, got " + std::to_string(lod));
    ExportInput input;
    if (fs::is_directory(path)) {
        std::vector<fs::path> files;
        for (const auto& entry : fs::recursive_directory_iterator(path))
            if (entry.is_regular_file() && is_tree_file(entry.path())) files.push_back(entry.path());
        std::sort(files.begin(), files.end());
        if (files.empty()) throw Error::input(path.string(), "folder holds no skeleton PLY, .tlobe, .dbf6 or .forest file");
        for (const auto& file : files) read_file_into(file, lod, input);
    } else {
        if (!fs::exists(path)) throw Error::input(path.string(), "no such file");
        read_file_into(path, lod, input);
    }
    if (input.trees.empty()) throw Error::input(path.string(), "holds no trees");
    make_names_unique(input.trees);
    return input;
}

}  // namespace treelobes::exporting
