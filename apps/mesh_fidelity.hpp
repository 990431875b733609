// How close one tree mesh is to another, as `treelobes rebuild` reports it for the rebuilt tree
// against the original and `treelobes compare` for any two meshes (docs/rebuild.md):
// Metro-style surface distances (Cignoni et al. 1998), silhouettes from the front, the side and
// the top, both as drawn and as crown outlines.
#pragma once

#include "core/triangle_mesh.hpp"
#include "render/image.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <utility>

namespace treelobes::cli {

struct MeshFidelityOptions {
    std::size_t samples = 20000;  // per surface, for the distances
    std::uint64_t seed = 1;
    int silhouette_px = 400;   // square masks per view
    int crown_closing_px = 8;  // 2 % of the mask: gaps narrower than this are inside the crown
};

// Bounds of the faces' vertices in world coordinates (origin + local).
std::pair<Eigen::Vector3d, Eigen::Vector3d> world_bounds(const TriangleMesh& mesh);

// `original_to_rebuilt`, `rebuilt_to_original`, `symmetric` distances (m and fractions of the
// original's bounding-box diagonal), `silhouette_iou` and `crown_silhouette_iou` per view
// (front, side, top; one orthographic camera per view framing the original). With `crowns`, also
// the picture of the crown outlines: one panel per view, each pixel coloured by which outline
// holds it (both, the original's only, the rebuilt's only), the IoU above, a legend below.
nlohmann::json mesh_fidelity(const TriangleMesh& original, const TriangleMesh& rebuilt, const MeshFidelityOptions& options,
                             render::Image* crowns = nullptr);

// The silhouette lines of the one-screen summaries (stdout).
void print_silhouettes(const nlohmann::json& fidelity);

}  // namespace treelobes::cli
