// The same coordinate reference system with its axes in metres, for a survey in feet: US State
// Plane tiles in feet, heights in US survey feet. treelobes measures in metres; `convert
// --to-metres` rewrites such a tile so that `tile` can read it. And the units of a CRS known only
// by its EPSG code, which its text does not name (core/crs_units.hpp reads those of a WKT). A
// projected CRS in another length unit is the same projection with its coordinates multiplied by
// that unit's size in metres, so the conversion is exact (no reprojection). PROJ reads the CRS (WKT 1 or 2, ESRI WKT, or an EPSG code
// from its registry) and writes the altered one; it stays private to the .cpp file.
#pragma once

#include "core/crs_units.hpp"
#include "core/point_cloud.hpp"

#include <string>

namespace treelobes {

struct MetricCrs {
    std::string wkt;              // the CRS with its axes in metres (WKT 1, GDAL flavour: what LAS readers take)
    double horizontal = 1.0;      // metres per unit of x and y before
    double vertical = 1.0;        // metres per unit of z before
    std::string horizontal_unit;  // the units before, by name
    std::string vertical_unit;
    // Where the vertical unit came from: "vertical CRS" (a compound CRS's vertical part), "CRS
    // axes" (a 3D CRS), or "assumed as horizontal" (a 2D CRS: z in the unit of x and y, as US
    // State Plane surveys in feet give it).
    std::string vertical_source;
};

// Throws Error(InvalidInput) naming `source` when the cloud has no CRS, PROJ cannot read it, or it
// is geographic (degrees: a reprojection, not a change of unit).
MetricCrs crs_in_metres(const Georeference& georef, const std::string& source);

// Horizontal and vertical units of a cloud's CRS: as its WKT names them (crs_horizontal_unit,
// crs_vertical_unit), else as the unit codes of its GeoTIFF keys do (a LAS 1.0-1.3 file, whose
// WKT is then "EPSG:nnnn"), else as PROJ reads the CRS (an EPSG code from its registry; across,
// the first axis's unit, angular for a geographic CRS; up, a compound CRS's vertical part's or a
// 3D CRS's third axis's). Empty where none of them names a unit.
CrsUnits crs_units_of(const Georeference& georef);

// The cloud's coordinates and LAS scale and offset multiplied into metres (the stored integers
// stay the same), its CRS replaced by `metric`'s WKT (the input's CRS records dropped).
void convert_to_metres(PointCloud& cloud, const MetricCrs& metric);

}  // namespace treelobes
