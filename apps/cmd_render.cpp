// `treelobes render INPUT... --out PREVIEW.png`: orthographic previews of point clouds, meshes
// and skeletons, one panel per input, side by side, all panels in the same frame and scale.
// --view front|side|top looks along +y, along -x or down; the panel takes the shape of the
// subject seen that way, so it fills the frame. --view orbit writes an animated PNG of the
// subject turning once around the vertical axis, at one scale in every frame. --color height|tree colours clouds by height or
// by their treeID attribute, radius|order colours skeletons by radius or branch order (inputs
// the colouring does not apply to keep their plain colour).
#include "apps/command.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/file_info.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "render/apng.hpp"
#include "render/colour_map.hpp"
#include "render/rasterizer.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
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
    std::string view;           // front, side, top, orbit (the first three override azimuth and elevation)
    int frames = 24;            // orbit: frames per turn
    int frame_ms = 100;         // orbit: time each frame is shown
    std::string colour = "plain";
};

using Drawable = std::variant<PointCloud, TriangleMesh, TreeGraph>;

Drawable load(const std::string& path) {
    const std::string kind = describe_file(path).kind;
    if (kind == "mesh") return read_mesh(path);
    if (kind == "skeleton") return read_skeleton_ply(path);
    return read_point_cloud(path);
}

// Calls `visit` with the world position of every point, vertex or skeleton node of `item`.
template <typename Visit>
void for_each_point(const Drawable& item, Visit&& visit) {
    std::visit(
        [&](const auto& thing) {
            using T = std::decay_t<decltype(thing)>;
            if constexpr (std::is_same_v<T, PointCloud>)
                for (const auto& p : thing.positions) visit(thing.origin + p.template cast<double>());
            else if constexpr (std::is_same_v<T, TriangleMesh>)
                for (const auto& p : thing.vertices) visit(thing.origin + p.template cast<double>());
            else
                for (const auto& n : thing.nodes) visit(thing.origin + n.position.template cast<double>());
        },
        item);
}

void bounds_of(const Drawable& item, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
    for_each_point(item, [&](const Eigen::Vector3d& q) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
    });
}

// Largest horizontal distance of any point of `items` from the vertical axis through `centre`:
// the radius the subject sweeps while it turns.
double swept_radius(const std::vector<Drawable>& items, const Eigen::Vector3d& centre) {
    double radius = 1e-6;
    for (const auto& item : items)
        for_each_point(item, [&](const Eigen::Vector3d& q) { radius = std::max(radius, (q - centre).head<2>().norm()); });
    return radius;
}

// Value of each point in [0, 1] (height) or a colour per tree id.
std::vector<render::Rgba> cloud_colours(const PointCloud& cloud, const std::string& colour, const std::string& path) {
    std::vector<render::Rgba> colours;
    if (colour == "height") {
        float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
        for (const auto& p : cloud.positions) lo = std::min(lo, p.z()), hi = std::max(hi, p.z());
        for (const auto& p : cloud.positions) colours.push_back(render::ramp_colour((p.z() - lo) / std::max(1e-6f, hi - lo)));
        return colours;
    }
    const auto tree_id = std::find_if(cloud.extras.begin(), cloud.extras.end(), [](const ExtraAttribute& a) {
        std::string name = a.name;
        std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
        return name == "treeid" || name == "tree_id" || name == "scalar_treeid";
    });
    if (tree_id == cloud.extras.end()) throw Error::input(path, "--color tree needs a treeID attribute (LAS extra bytes or PLY scalar_treeID)");
    for (double id : tree_id->values) colours.push_back(render::id_colour(static_cast<long long>(id)));
    return colours;
}

std::vector<Eigen::Vector3d> world_points(const PointCloud& cloud) {
    std::vector<Eigen::Vector3d> points;
    points.reserve(cloud.size());
    for (const auto& p : cloud.positions) points.push_back(cloud.origin + p.template cast<double>());
    return points;
}

// Each edge coloured by its child node's radius (relative to the largest) or branch order.
void draw_coloured_skeleton(render::Rasterizer& r, const TreeGraph& tree, const std::string& colour) {
    const std::vector<int> orders = tree.branch_orders();
    const int max_order = std::max(1, *std::max_element(orders.begin(), orders.end()));
    float max_radius = 1e-9f;
    for (const auto& n : tree.nodes) max_radius = std::max(max_radius, n.radius);
    for (std::size_t i = 1; i < tree.size(); ++i) {
        const auto& node = tree.nodes[i];
        const double t = colour == "radius" ? node.radius / max_radius : static_cast<double>(orders[i]) / max_order;
        r.draw_segment(tree.origin + tree.nodes[node.parent].position.cast<double>(), tree.origin + node.position.cast<double>(),
                       render::ramp_colour(t));
    }
}

render::Image draw(const Drawable& item, const std::string& path, const RenderOptions& options, const render::View& view,
                   int width, int height) {
    render::Rasterizer r(width, height, view);
    const std::string& colour = options.colour;
    std::visit(
        [&](const auto& thing) {
            using T = std::decay_t<decltype(thing)>;
            if constexpr (std::is_same_v<T, PointCloud>) {
                if (colour == "height" || colour == "tree") r.draw_points(world_points(thing), cloud_colours(thing, colour, path), 2);
                else r.draw_points(thing, {40, 90, 40, 255}, 2);
            } else if constexpr (std::is_same_v<T, TriangleMesh>) r.draw_mesh(thing, {150, 110, 70, 255});
            else if (colour == "radius" || colour == "order") draw_coloured_skeleton(r, thing, colour);
            else r.draw_skeleton(thing, {120, 30, 20, 255});
        },
        item);
    return r.image();
}

render::View make_view(const RenderOptions& o, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    if (o.view == "front") return render::View::side(lo, hi, 0, 0);
    if (o.view == "side") return render::View::side(lo, hi, 270, 0);
    if (o.view == "top") return render::View::side(lo, hi, 0, 90);
    return render::View::side(lo, hi, o.azimuth, o.elevation);
}

// The inputs side by side, all in `view`; each panel takes the subject's shape on the image
// (`view.aspect()`), so it fills the frame.
render::Image draw_panels(const std::vector<Drawable>& items, const RenderOptions& options, const render::View& view) {
    const int width = std::clamp(static_cast<int>(std::lround(options.size * view.aspect())), 64, 4096);
    std::vector<render::Image> panels;
    for (std::size_t i = 0; i < items.size(); ++i) panels.push_back(draw(items[i], options.inputs[i], options, view, width, options.size));
    return render::side_by_side(panels);
}

// One turn around the vertical axis through the centre of [lo, hi], starting at --azimuth. Every
// frame frames the cylinder the subject sweeps (its swept radius across, its height seen at
// --elevation up), so the scale is the same in all frames and the subject does not pulse.
std::vector<render::Image> draw_orbit(const std::vector<Drawable>& items, const RenderOptions& options, const Eigen::Vector3d& lo,
                                      const Eigen::Vector3d& hi) {
    const double radius = swept_radius(items, 0.5 * (lo + hi));
    const double elevation = options.elevation * M_PI / 180.0;
    std::vector<render::Image> frames;
    for (int k = 0; k < options.frames; ++k) {
        render::View view = render::View::side(lo, hi, options.azimuth + 360.0 * k / options.frames, options.elevation);
        view.half_width = radius;
        view.half_height = 0.5 * (hi.z() - lo.z()) * std::cos(elevation) + radius * std::abs(std::sin(elevation));
        frames.push_back(draw_panels(items, options, view));
    }
    return frames;
}

int run_render(const RenderOptions& options, const GlobalOptions& global) {
    std::vector<Drawable> items;
    for (const auto& input : options.inputs) items.push_back(load(input));
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const auto& item : items) bounds_of(item, lo, hi);
    if (!lo.allFinite() || (lo.array() > hi.array()).any()) throw Error::input(options.inputs.front(), "nothing to draw");
    nlohmann::json summary{{"out", options.out}, {"panels", items.size()}};
    if (options.view == "orbit") {
        const std::vector<render::Image> frames = draw_orbit(items, options, lo, hi);
        render::write_apng(frames, options.frame_ms, options.out);
        summary["frames"] = frames.size();
        summary["width"] = frames.front().width;
        summary["height"] = frames.front().height;
    } else {
        const render::Image image = draw_panels(items, options, make_view(options, lo, hi));
        render::write_png(image, options.out);
        summary["width"] = image.width;
        summary["height"] = image.height;
    }
    if (global.json) std::cout << summary.dump(2) << "\n";
    else
        std::cout << "wrote " << options.out << " (" << items.size() << " panel(s)"
                  << (summary.contains("frames") ? ", " + summary["frames"].dump() + " frames" : std::string()) << ")\n";
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
    sub->add_option("--view", options->view, "front (along +y), side (along -x) or top (down), overriding --azimuth/--elevation; orbit: an animated PNG turning once around the vertical axis from --azimuth at --elevation")
        ->check(CLI::IsMember({"front", "side", "top", "orbit"}));
    sub->add_option("--frames", options->frames, "--view orbit: frames per turn")->check(CLI::Range(2, 360))->capture_default_str();
    sub->add_option("--frame-ms", options->frame_ms, "--view orbit: milliseconds each frame is shown")->check(CLI::Range(10, 10000))->capture_default_str();
    sub->add_option("--color", options->colour, "plain; clouds: height or tree (treeID); skeletons: radius or order (branch order)")
        ->check(CLI::IsMember({"plain", "height", "tree", "radius", "order"}))->capture_default_str();
    sub->callback([options, &global, &job] { job = [options, &global] { return run_render(*options, global); }; });
}

}  // namespace treelobes::cli
