// GeoJSON FeatureCollections as treelobes writes them (trees.geojson, crowns.geojson of `tile`
// and of `merge`): one layout for every writer, so that a merged survey's files read like a
// tile's.
#pragma once

#include <nlohmann/json_fwd.hpp>

#include <string>

namespace treelobes {

// A FeatureCollection of `features` (a JSON array), with the CRS as WKT in a "crs_wkt" member
// when it is known (RFC 7946 has no CRS member: readers that expect WGS 84 must be told), as
// text ending in a newline.
std::string feature_collection(nlohmann::json features, const std::string& crs_wkt);

}  // namespace treelobes
