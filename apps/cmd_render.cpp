// `treelobes render INPUT... --out PREVIEW.png`: orthographic previews of point clouds, meshes
// and skeletons, one panel per input, side by side, all panels in the same frame and scale.
#include "apps/command.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/file_info.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "render/rasterizer.hpp"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <variant>

namespace treelobes::cli {

namespace {

struct RenderOptions {
    std::vector<std::string> inputs;
    std::string out;
    int size = 800;             // panel height in pixels
    double azimuth = 0;         // degrees around the vertical axis
    double elevation = 10;      // degrees above the horizon
};

using Drawable = std::variant<PointCloud, TriangleMesh, TreeGraph>;

Drawable load(const std::string& path) {
    const std::string kind = describe_file(path).kind;
    if (kind == "mesh") return read_mesh(path);
    if (kind == "skeleton") return read_skeleton_ply(path);
    return read_point_cloud(path);
}

void extend(Eigen::Vector3d& lo, Eigen::Vector3d& hi, const Eigen::Vector3d& origin, const Eigen::Vector3f& p) {
    const Eigen::Vector3d q = origin + p.cast<double>();
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
}

void bounds_of(const Drawable& item, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
    std::visit(
        [&](const auto& thing) {
            using T = std::decay_t<decltype(thing)>;
            if constexpr (std::is_same_v<T, PointCloud>)
                for (const auto& p : thing.positions) extend(lo, hi, thing.origin, p);
            else if constexpr (std::is_same_v<T, TriangleMesh>)
                for (const auto& p : thing.vertices) extend(lo, hi, thing.origin, p);
            else
                for (const auto& n : thing.nodes) extend(lo, hi, thing.origin, n.position);
        },
        item);
}

render::Image draw(const Drawable& item, const render::View& view, int width, int height) {
    render::Rasterizer r(width, height, view);
    std::visit(
        [&](const auto& thing) {
            using T = std::decay_t<decltype(thing)>;
            if constexpr (std::is_same_v<T, PointCloud>) r.draw_points(thing, {40, 90, 40, 255}, 2);
            else if constexpr (std::is_same_v<T, TriangleMesh>) r.draw_mesh(thing, {150, 110, 70, 255});
            else r.draw_skeleton(thing, {120, 30, 20, 255});
        },
        item);
    return r.image();
}

int run_render(const RenderOptions& options, const GlobalOptions& global) {
    std::vector<Drawable> items;
    for (const auto& input : options.inputs) items.push_back(load(input));
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const auto& item : items) bounds_of(item, lo, hi);
    if (!lo.allFinite() || (lo.array() > hi.array()).any()) throw Error::input(options.inputs.front(), "nothing to draw");
    const render::View view = render::View::side(lo, hi, options.azimuth, options.elevation);
    // Panels shaped like the subject seen from this view, so that it fills the frame.
    const int width = std::max(64, static_cast<int>(options.size * std::max(0.3, view.aspect())));
    std::vector<render::Image> panels;
    for (const auto& item : items) panels.push_back(draw(item, view, std::min(width, 4096), options.size));
    render::write_png(render::side_by_side(panels), options.out);
    if (global.json) std::cout << nlohmann::json{{"out", options.out}, {"panels", panels.size()}}.dump(2) << "\n";
    else std::cout << "wrote " << options.out << " (" << panels.size() << " panel(s))\n";
    return 0;
}

}  // namespace

void add_render_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<RenderOptions>();
    CLI::App* sub = app.add_subcommand("render", "Draw point clouds, meshes and skeletons side by side into a PNG");
    sub->add_option("inputs", options->inputs, "Point clouds, meshes (PLY/OBJ/OFF) or skeleton PLYs")->required();
    sub->add_option("--out,-o", options->out, "Output PNG")->required();
    sub->add_option("--size", options->size, "Panel height in pixels")->check(CLI::Range(64, 4096))->capture_default_str();
    sub->add_option("--azimuth", options->azimuth, "View direction around the vertical axis, degrees")->capture_default_str();
    sub->add_option("--elevation", options->elevation, "View elevation above the horizon, degrees")
        ->check(CLI::Range(-90.0, 90.0))->capture_default_str();
    sub->callback([options, &global, &job] { job = [options, &global] { return run_render(*options, global); }; });
}

}  // namespace treelobes::cli
