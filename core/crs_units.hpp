// The units a coordinate reference system measures lengths and heights in, read from its WKT or
// from the unit codes of a LAS file's GeoTIFF keys. The pipeline takes coordinates as metres; a
// tile in feet (US State Plane surveys), with heights in feet (a compound CRS whose vertical part
// is in feet) or in degrees (a geographic CRS) must be reprojected first, and `tile` says so
// instead of measuring trees 3.28 times too tall.
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

// The unit of a compound CRS's vertical part (WKT 1 VERT_CS, WKT 2 VERTCRS: the first unit of its
// CS); nullopt when the text has no vertical part or it names no unit.
std::optional<CrsUnit> crs_vertical_unit(std::string_view wkt);

// A linear unit by its EPSG code, as GeoTIFF keys give it (ProjLinearUnitsGeoKey 3076,
// VerticalUnitsGeoKey 4099): metre 9001, foot 9002, US survey foot 9003, Clarke's foot 9005,
// kilometre 9036, British foot (Sears 1922) 9041, British foot (1936) 9070, yard 9096; nullopt for
// other codes.
std::optional<CrsUnit> epsg_linear_unit(int code);

// Horizontal and vertical units of a CRS; crs_units_of (core/crs_metres.hpp) gives a cloud's.
struct CrsUnits {
    std::optional<CrsUnit> horizontal;
    std::optional<CrsUnit> vertical;
};

}  // namespace treelobes
