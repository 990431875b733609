#include "core/geojson.hpp"

#include <nlohmann/json.hpp>

namespace treelobes {

std::string feature_collection(nlohmann::json features, const std::string& crs_wkt) {
    nlohmann::json collection = {{"type", "FeatureCollection"}, {"features", std::move(features)}};
    if (!crs_wkt.empty()) collection["crs_wkt"] = crs_wkt;
    return collection.dump(1) + "\n";
}

}  // namespace treelobes
