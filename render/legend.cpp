#include "render/legend.hpp"

#include "render/text.hpp"

#include <algorithm>

namespace treelobes::render {

Image draw_legend(const std::vector<LegendEntry>& entries, int scale, Rgba background) {
    const int line = text_height(scale) + 3 * scale, swatch = text_height(scale), pad = 3 * scale;
    int width = 0;
    for (const auto& entry : entries) width = std::max(width, text_width(entry.label, scale));
    Image legend(pad + swatch + pad + width + pad, pad + std::max<int>(1, static_cast<int>(entries.size())) * line, background);
    int y = pad;
    for (const auto& entry : entries) {
        legend.fill_rect(pad, y, pad + swatch, y + swatch, {60, 60, 60, 255});  // outline, visible for pale colours
        legend.fill_rect(pad + 1, y + 1, pad + swatch - 1, y + swatch - 1, entry.colour);
        draw_text(legend, pad + swatch + pad, y, entry.label, scale, {20, 20, 20, 255});
        y += line;
    }
    return legend;
}

Image with_legend(const Image& image, const std::vector<LegendEntry>& entries, int scale, Rgba background) {
    return side_by_side({image, draw_legend(entries, scale, background)}, background);
}

}  // namespace treelobes::render
