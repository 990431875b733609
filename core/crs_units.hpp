// The unit a coordinate reference system measures lengths in, read from its WKT. The pipeline
// takes coordinates as metres; a tile in feet (US State Plane surveys) or in degrees (a geographic
// CRS) must be reprojected first, and `tile` says so instead of measuring trees 3.28 times too
// tall.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace treelobes {

struct CrsUnit {
    std::string name;      // as the WKT spells it: "metre", "foot", "US survey foot", "degree"
    double metres = 1.0;   // metres per unit (0 for an angular unit)
    bool angular = false;  // a geographic CRS: coordinates in degrees
    bool is_metre() const { return !angular && metres > 0.9999 && metres < 1.0001; }
};

// The horizontal unit of a WKT 1 (PROJCS: its own UNIT; GEOGCS alone: angular) or WKT 2
// (PROJCRS: the first unit of its coordinate system, CS; GEOGCRS alone: angular) text, a compound
// CRS's horizontal part; nullopt when the text names none (empty, "EPSG:26917", unreadable).
std::optional<CrsUnit> crs_horizontal_unit(std::string_view wkt);

}  // namespace treelobes
