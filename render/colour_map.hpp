// Colours for values (a perceptually ordered ramp) and for ids (distinct hues), for previews
// coloured by height, radius, branch order or tree.
#pragma once

#include "render/image.hpp"

namespace treelobes::render {

// t in [0, 1] (clamped) on the viridis ramp (dark blue -> green -> yellow).
Rgba ramp_colour(double t);
// A distinct, saturated colour per id (hue steps of the golden angle); id 0 ("no tree") is grey.
Rgba id_colour(long long id);

}  // namespace treelobes::render
