#include "core/georef_sidecar.hpp"

#include "core/atomic_file.hpp"

#include <nlohmann/json.hpp>

#include <sstream>

namespace treelobes {

namespace {
constexpr const char* kOriginTag = "treelobes_origin";
}

std::optional<Eigen::Vector3d> read_origin_comment(const std::vector<std::string>& comments) {
    for (const auto& comment : comments) {
        std::istringstream words(comment);
        std::string tag;
        Eigen::Vector3d origin;
        if (words >> tag && tag == kOriginTag && words >> origin.x() >> origin.y() >> origin.z() && origin.allFinite())
            return origin;
    }
    return std::nullopt;
}

void write_origin_comment(const Eigen::Vector3d& origin, std::vector<std::string>& comments) {
    if (origin.isZero()) return;
    std::ostringstream line;
    line.precision(17);
    line << kOriginTag << " " << origin.x() << " " << origin.y() << " " << origin.z();
    comments.push_back(line.str());
}

std::filesystem::path georef_sidecar_path(const std::filesystem::path& data_file) {
    return data_file.parent_path() / (data_file.stem().string() + ".georef.json");
}

void write_georef_sidecar(const std::filesystem::path& data_file, const Eigen::Vector3d& origin, const Georeference& georef) {
    if (origin.isZero() && georef.crs_wkt.empty()) return;
    const nlohmann::json sidecar = {{"origin", {origin.x(), origin.y(), origin.z()}},
                                    {"crs_wkt", georef.crs_wkt},
                                    {"units", "metre"},
                                    {"note", "coordinates in " + data_file.filename().string() + " are relative to origin"}};
    write_file_atomically(georef_sidecar_path(data_file), sidecar.dump(2) + "\n");
}

}  // namespace treelobes
