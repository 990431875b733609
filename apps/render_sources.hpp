// What `treelobes render` reads besides single files: a `tile` output folder (points.las with
// treeID + trees.csv) and the species of points (a cloud's `species` attribute or the trees.csv
// species of each point's tree), with one stable colour per species name.
#pragma once

#include "core/point_cloud.hpp"
#include "render/image.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::cli {

struct TileTree {
    int id = 0;
    std::string species;  // empty when the tile ran without a species model
    double height_m = 0;  // NaN when trees.csv has none
};

struct TileOutput {
    PointCloud points;            // points.las
    std::vector<TileTree> trees;  // trees.csv, sorted by id
};

// A folder holding the trees.csv and points.las that `treelobes tile` writes.
bool is_tile_output(const std::filesystem::path& path);
// Throws Error::input naming the file for a missing or malformed trees.csv / points.las.
TileOutput read_tile_output(const std::filesystem::path& dir);

// The tree id of every point (LAS extra bytes treeID, PLY scalar_treeID); nullptr when absent.
const ExtraAttribute* tree_id_attribute(const PointCloud& cloud);

// Species per point: an index into `names` (sorted), -1 where unknown.
struct PointSpecies {
    std::vector<std::string> names;
    std::vector<int> of_point;
};

// From the trees' species through each point's tree id (when `trees` is not null), else from the
// cloud's `species` attribute (ids of config/species.yaml, as synth writes them). Throws
// Error::input naming `path` when there is neither.
PointSpecies point_species(const PointCloud& cloud, const std::vector<TileTree>* trees, const std::string& path);

// One colour per species name, the same in every picture: a species of config/species.yaml
// takes the distinct colour of its stable library id, another name a colour from a hash of it.
render::Rgba species_colour(const std::string& name);
// Grey: points of no tree or of a tree without species.
inline constexpr render::Rgba unknown_species_colour{170, 170, 170, 255};

}  // namespace treelobes::cli
