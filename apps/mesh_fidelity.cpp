#include "apps/mesh_fidelity.hpp"

#include "apps/summary_values.hpp"
#include "core/error.hpp"
#include "core/point_cloud.hpp"
#include "geometry/mesh_distance.hpp"
#include "render/rasterizer.hpp"
#include "render/text.hpp"
#include "synth/mesh_sampling.hpp"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace treelobes::cli {

namespace {

using json = nlohmann::json;

json distance_json(const DistanceSummary& d, double diagonal) {
    return {{"mean", rounded(d.mean, 4)},
            {"median", rounded(d.median, 4)},
            {"p95", rounded(d.p95, 4)},
            {"max", rounded(d.max, 4)},
            {"mean_of_diagonal", rounded(d.mean / diagonal, 5)},
            {"p95_of_diagonal", rounded(d.p95 / diagonal, 5)},
            {"max_of_diagonal", rounded(d.max / diagonal, 5)}};
}

// Metro-style comparison (Cignoni et al. 1998): both surfaces sampled alike, each sample's
// distance to the other surface; the symmetric figures take the worse direction for the
// percentile and the Hausdorff distance and the mean of both directions for the mean.
json compare_surfaces(const TriangleMesh& original, const TriangleMesh& rebuilt, const MeshFidelityOptions& options, double diagonal) {
    const std::vector<std::uint8_t> no_labels_a(original.faces.size(), 1), no_labels_b(rebuilt.faces.size(), 1);
    const PointCloud on_original = synth::sample_surface(original, no_labels_a, options.samples, options.seed);
    const PointCloud on_rebuilt = synth::sample_surface(rebuilt, no_labels_b, options.samples, options.seed + 1);
    const DistanceSummary forward = summarise_distances(MeshDistance(rebuilt).distances(on_original));
    const DistanceSummary backward = summarise_distances(MeshDistance(original).distances(on_rebuilt));
    DistanceSummary symmetric;
    symmetric.count = forward.count + backward.count;
    symmetric.mean = 0.5 * (forward.mean + backward.mean);
    symmetric.median = 0.5 * (forward.median + backward.median);
    symmetric.p95 = std::max(forward.p95, backward.p95);
    symmetric.max = std::max(forward.max, backward.max);
    return {{"samples_per_surface", options.samples},
            {"original_to_rebuilt", distance_json(forward, diagonal)},
            {"rebuilt_to_original", distance_json(backward, diagonal)},
            {"symmetric", distance_json(symmetric, diagonal)}};
}

constexpr render::Rgba kWhite{255, 255, 255, 255}, kInk{30, 30, 30, 255};
constexpr render::Rgba kBoth{190, 190, 190, 255}, kOriginalOnly{230, 120, 20, 255}, kRebuiltOnly{40, 100, 200, 255};
constexpr int kTextScale = 2, kMargin = 8;

// One view's crown outlines, each pixel coloured by which of them holds it, the IoU above.
render::Image outline_panel(const std::vector<bool>& original, const std::vector<bool>& rebuilt, int size, const std::string& label) {
    const int top = 2 * kMargin + render::text_height(kTextScale);
    render::Image panel(size, top + size, kWhite);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * size + x;
            if (original[i] || rebuilt[i])
                panel.set(x, top + y, original[i] && rebuilt[i] ? kBoth : original[i] ? kOriginalOnly : kRebuiltOnly);
        }
    render::draw_text(panel, kMargin, kMargin, label, kTextScale, kInk);
    return panel;
}

// The three panels side by side over a legend of the colours.
render::Image with_colour_key(const std::vector<render::Image>& panels) {
    const render::Image row = render::side_by_side(panels);
    const int line = render::text_height(kTextScale), height = row.height + 2 * kMargin + line;
    render::Image image(row.width, height, kWhite);
    for (int y = 0; y < row.height; ++y)
        for (int x = 0; x < row.width; ++x) image.set(x, y, row.at(x, y));
    int x = kMargin;
    const int y = row.height + kMargin;
    for (const auto& [colour, text] : {std::pair{kBoth, "BOTH"}, {kOriginalOnly, "ORIGINAL ONLY"}, {kRebuiltOnly, "REBUILT ONLY"}}) {
        image.fill_rect(x, y, x + line, y + line, colour);
        render::draw_text(image, x + line + kMargin / 2, y, text, kTextScale, kInk);
        x += line + kMargin + render::text_width(text, kTextScale) + 3 * kMargin;
    }
    return image;
}

// Silhouettes of both meshes from the front, the side and the top, one camera per view framing
// the original: the IoU of the masks as drawn and of their crown outlines.
void add_silhouettes(json& fidelity, const TriangleMesh& original, const TriangleMesh& rebuilt, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi, const MeshFidelityOptions& options, render::Image* picture) {
    const int size = options.silhouette_px;
    render::View top;
    top.forward = Eigen::Vector3d(0, 0, -1);
    top.up = Eigen::Vector3d(0, 1, 0);
    top.lo = lo;
    top.hi = hi;
    const std::pair<const char*, render::View> views[] = {
            {"front", render::View::side(lo, hi, 0, 0)}, {"side", render::View::side(lo, hi, 90, 0)}, {"top", top}};
    json drawn = json::object(), crowns = json::object();
    std::vector<render::Image> panels;
    for (const auto& [name, view] : views) {
        render::Rasterizer a(size, size, view), b(size, size, view);
        a.draw_mesh(original, {0, 0, 0, 255});
        b.draw_mesh(rebuilt, {0, 0, 0, 255});
        const std::vector<bool> mask_a = a.coverage(), mask_b = b.coverage();
        drawn[name] = rounded(render::silhouette_iou(mask_a, mask_b), 4);
        const std::vector<bool> crown_a = render::crown_outline(mask_a, size, size, options.crown_closing_px),
                                crown_b = render::crown_outline(mask_b, size, size, options.crown_closing_px);
        const double iou = render::silhouette_iou(crown_a, crown_b);
        crowns[name] = rounded(iou, 4);
        char label[64];
        std::snprintf(label, sizeof label, "%s  CROWN IOU %.2f", name, iou);
        if (picture) panels.push_back(outline_panel(crown_a, crown_b, size, label));
    }
    if (picture) *picture = with_colour_key(panels);
    fidelity["silhouette_px"] = size;
    fidelity["silhouette_iou"] = drawn;
    fidelity["crown_closing_px"] = options.crown_closing_px;
    fidelity["crown_silhouette_iou"] = crowns;
}

}  // namespace

std::pair<Eigen::Vector3d, Eigen::Vector3d> world_bounds(const TriangleMesh& mesh) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const auto& face : mesh.faces)
        for (int c : face) {
            const Eigen::Vector3d p = mesh.origin + mesh.vertices[c].cast<double>();
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    return {lo, hi};
}

json mesh_fidelity(const TriangleMesh& original, const TriangleMesh& rebuilt, const MeshFidelityOptions& options, render::Image* crowns) {
    if (original.faces.empty() || rebuilt.faces.empty()) throw Error(ExitCode::Internal, "mesh_fidelity: a mesh without faces");
    const auto [lo, hi] = world_bounds(original);
    const double diagonal = (hi - lo).norm();
    json fidelity = compare_surfaces(original, rebuilt, options, diagonal);
    add_silhouettes(fidelity, original, rebuilt, lo, hi, options, crowns);
    return fidelity;
}

void print_silhouettes(const json& fidelity) {
    for (const char* key : {"silhouette_iou", "crown_silhouette_iou"}) {
        const json& iou = fidelity[key];
        std::printf("  %-19s front %.2f, side %.2f, top %.2f\n",
                    key == std::string("silhouette_iou") ? "silhouette IoU" : "crown outline IoU", iou["front"].get<double>(),
                    iou["side"].get<double>(), iou["top"].get<double>());
    }
}

}  // namespace treelobes::cli
