// CityJSON 2.0 (https://www.cityjson.org/specs/2.0.1/) of one or more trees: one
// SolitaryVegetationObject per tree with
//   attributes  species (when known), height, trunkDiameter, crownDiameter (metres, the
//               CityGML vegetation attributes) and our measures: crownBaseHeight, crownVolume,
//               woodVolume, skeletonLength, branchCount, lobeCount;
//   geometry    LoD 1: the crown as a Solid (its convex hull, export/tree_measures.hpp);
//               LoD 2: the branch tubes (and lobes) as a MultiSurface of triangles.
// Vertices are integers with `transform` (scale 1 mm, translate = the floored minimum corner of
// the trees, nodes widened by their radii);
// duplicates are merged and triangles that collapse on the millimetre grid are dropped.
// metadata.referenceSystem is the OGC CRS URL when the CRS has an EPSG code.
//
// With `instances`, LoD 2 is a GeometryInstance of a per-species template instead (CityJSON 2.0
// §2.7 "Geometry templates"): "geometry-templates" holds one MultiSurface per species (sorted by
// name, trees without species sharing the first, "" key): the LoD 2 geometry of the species' tree of
// median height, in metres relative to its stem base. Each tree refers to its species' template
// with its stem base as the reference point (a vertex) and a transformationMatrix scaling the
// template to the tree: x and y by crownDiameter / the template's, z by height / the template's.
#pragma once

#include "export/tree_input.hpp"

#include <string>
#include <vector>

namespace treelobes::exporting {

struct CityJsonOptions {
    int branch_sides = 6;    // tube sides of the LoD 2 branches
    bool instances = false;  // LoD 2 as per-species GeometryInstances of templates
};

// The document's text (deterministic). Trees are validated as they are measured.
std::string cityjson_text(const std::vector<ExportTree>& trees, const std::string& crs, const CityJsonOptions& options = {});

// What the schema cannot say, checked on a document's text: every vertex index in range, every
// Solid shell closed (each directed edge used once, its reverse once), no ring repeating a
// vertex; for GeometryInstances the template index within the templates, the reference point
// within the vertices, a finite affine matrix (last row 0 0 0 1), and every template's indices
// within "vertices-templates". Returns the problems found (empty: fine); Error(InvalidInput) if it is not JSON.
std::vector<std::string> check_cityjson(const std::string& text);

}  // namespace treelobes::exporting
