// Cutting big or irregular point clouds into square tiles that a batch can run one by one.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace treelobes::survey {

struct RetileOptions {
    double size = 100.0;          // tile side, metres (in the inputs' CRS units)
    std::string prefix = "tile";  // file names: <prefix>_<x>_<y>.las, x y = the lower-left corner
};

struct RetiledTile {
    std::filesystem::path path;
    double x = 0, y = 0;  // lower-left corner, original coordinates
    std::size_t points = 0;
};

// Every point goes to the square [x, x + size) x [y, y + size) on the grid anchored at 0, 0 that
// holds it; tiles without points are not written. Outputs are LAS 1.4 with the first input's
// scale, offset (when it fits), point format, CRS and attributes. Inputs are read one at a time,
// but the tiles are held until all inputs are read (a tile may draw on several inputs), so memory
// grows with the survey: check the inputs' size with --max-memory first.
// Throws Error(InvalidInput) when inputs disagree on the CRS or on their attributes.
std::vector<RetiledTile> retile(const std::vector<std::filesystem::path>& inputs, const RetileOptions& options,
                                const std::filesystem::path& out_dir);

// "<prefix>_<x>_<y>": corners in whole units when the size is whole, else with centimetres.
std::string retiled_name(const std::string& prefix, double x, double y, double size);

}  // namespace treelobes::survey
