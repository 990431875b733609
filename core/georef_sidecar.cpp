#include "core/georef_sidecar.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <nlohmann/json.hpp>

#include <regex>
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
        if (words >> tag && tag == kOriginTag && words >> origin.x() >> origin.y() >> origin.z() && origin.allFinite()) return origin;
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

std::optional<GeorefSidecar> read_georef_sidecar(const std::filesystem::path& data_file) {
    const std::filesystem::path path = georef_sidecar_path(data_file);
    if (!std::filesystem::is_regular_file(path)) return std::nullopt;
    GeorefSidecar sidecar;
    try {
        const nlohmann::json j = nlohmann::json::parse(read_file(path));
        if (j.contains("origin")) {
            const auto& o = j.at("origin");
            sidecar.origin = {o.at(0).get<double>(), o.at(1).get<double>(), o.at(2).get<double>()};
        }
        if (j.contains("crs_wkt")) sidecar.crs_wkt = j.at("crs_wkt").get<std::string>();
    } catch (const nlohmann::json::exception& e) {
        throw Error::input(path.string(), std::string("not a georef sidecar: ") + e.what());
    }
    if (!sidecar.origin.allFinite()) throw Error::input(path.string(), "origin is not finite");
    return sidecar;
}

std::string epsg_code(const std::string& crs) {
    static const std::regex short_form(R"(^\s*EPSG:(\d+)\s*$)", std::regex::icase);
    static const std::regex wkt_form(R"re((?:AUTHORITY|ID)\[\s*"EPSG"\s*,\s*"?(\d+)"?\s*\])re", std::regex::icase);
    std::smatch match;
    if (std::regex_match(crs, match, short_form)) return match[1];
    std::string code;
    for (auto it = std::sregex_iterator(crs.begin(), crs.end(), wkt_form); it != std::sregex_iterator(); ++it) code = (*it)[1];
    return code;
}

}  // namespace treelobes
