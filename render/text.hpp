// Text on images with a 3x5 pixel bitmap font (digits, capital letters, a few signs; lower
// case is drawn as upper case): labels of plots and maps without a font library.
#pragma once

#include "render/image.hpp"

#include <string>

namespace treelobes::render {

// Draws `text` with its top-left corner at (x, y), each font pixel `scale` image pixels wide.
// Characters the font lacks leave a blank.
void draw_text(Image& image, int x, int y, const std::string& text, int scale, Rgba colour);
// Width in pixels of `text` drawn at `scale` (4 font pixels per character, spacing included).
int text_width(const std::string& text, int scale);
// Height in pixels of one line drawn at `scale`.
inline int text_height(int scale) { return 5 * scale; }

}  // namespace treelobes::render
