// A colour legend (a swatch and a label per entry, one per line) beside a picture, drawn with
// the bitmap font of render/text.hpp.
#pragma once

#include "render/image.hpp"

#include <string>
#include <vector>

namespace treelobes::render {

struct LegendEntry {
    std::string label;
    Rgba colour{0, 0, 0, 255};
};

// The legend alone: entries top to bottom, font pixels `scale` image pixels wide, on `background`.
Image draw_legend(const std::vector<LegendEntry>& entries, int scale, Rgba background = {255, 255, 255, 255});
// `image` with the legend (drawn at `scale`) to its right.
Image with_legend(const Image& image, const std::vector<LegendEntry>& entries, int scale, Rgba background = {255, 255, 255, 255});

}  // namespace treelobes::render
