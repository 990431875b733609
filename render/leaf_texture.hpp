// A leaf drawn procedurally into a small RGBA texture (transparent around the leaf), for leaf
// cards in exported models: an alpha-masked quad then shows a leaf instead of a green square.
#pragma once

#include "render/image.hpp"

namespace treelobes::render {

// `size` x `size` pixels (a power of two suits mipmapping): an ovate blade pointing up (its tip
// at row 0), a short petiole at the bottom centre, a lighter midrib and side veins, darker toward
// the margin. Alpha is 255 on the leaf and 0 elsewhere (no partial alpha, for alpha-mask
// materials). Deterministic.
Image leaf_texture(int size = 64);

}  // namespace treelobes::render
