// `treelobes render INPUT... --out PREVIEW.png`: orthographic previews of point clouds, meshes,
// skeletons and tile outputs, one panel per input, side by side, all panels in the same frame and
// scale. --view front|side|top looks along +y, along -x or down; the panel takes the shape of the
// subject seen that way, so it fills the frame. --view orbit writes an animated PNG of the
// subject turning once around the vertical axis, at one scale in every frame. --color
// height|tree|species colours clouds by height, treeID or species (with a legend), radius|order
// colours skeletons by radius or branch order (inputs the colouring does not apply to keep their
// plain colour). --contact-sheet draws every tree of a tile output folder in its own labelled
// panel.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/render_sources.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/file_info.hpp"
#include "core/mesh_io.hpp"
#include "core/skeleton_io.hpp"
#include "render/apng.hpp"
#include "render/colour_map.hpp"
#include "render/legend.hpp"
#include "render/rasterizer.hpp"
#include "render/text.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <variant>

namespace treelobes::cli {

namespace {

struct RenderOptions {
    std::vector<std::string> inputs;
    std::string out;
    int size = 800;         // panel height in pixels
    double azimuth = 0;     // degrees around the vertical axis
    double elevation = 10;  // degrees above the horizon
    std::string view;       // front, side, top, orbit (the first three override azimuth and elevation)
    int frames = 24;        // orbit: frames per turn
    int frame_ms = 100;     // orbit: time each frame is shown
    std::string colour = "plain";
    bool contact_sheet = false;  // one labelled panel per tree of a tile output folder
    int columns = 0;             // contact sheet columns (0: about square)
};

using Drawable = std::variant<PointCloud, TriangleMesh, TreeGraph>;

// One thing to draw, with the colour of each point when the colouring applies to it.
struct Subject {
    Drawable item;
    std::string path;
    std::vector<render::Rgba> point_colours;  // clouds coloured by height, tree or species
};

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

// Largest horizontal distance of any point of `subjects` from the vertical axis through
// `centre`: the radius the subject sweeps while it turns.
double swept_radius(const std::vector<Subject>& subjects, const Eigen::Vector3d& centre) {
    double radius = 1e-6;
    for (const auto& subject : subjects)
        for_each_point(subject.item, [&](const Eigen::Vector3d& q) { radius = std::max(radius, (q - centre).head<2>().norm()); });
    return radius;
}

std::vector<render::Rgba> height_colours(const PointCloud& cloud) {
    float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
    for (const auto& p : cloud.positions) lo = std::min(lo, p.z()), hi = std::max(hi, p.z());
    std::vector<render::Rgba> colours;
    colours.reserve(cloud.size());
    for (const auto& p : cloud.positions) colours.push_back(render::ramp_colour((p.z() - lo) / std::max(1e-6f, hi - lo)));
    return colours;
}

std::vector<render::Rgba> tree_colours(const PointCloud& cloud, const std::string& path) {
    const ExtraAttribute* tree_id = tree_id_attribute(cloud);
    if (!tree_id) throw Error::input(path, "--color tree needs a treeID attribute (LAS extra bytes or PLY scalar_treeID)");
    std::vector<render::Rgba> colours;
    colours.reserve(cloud.size());
    for (double id : tree_id->values) colours.push_back(render::id_colour(static_cast<long long>(id)));
    return colours;
}

// Species colours per point; adds the species seen to `legend` (name -> colour).
std::vector<render::Rgba> species_colours(const PointCloud& cloud, const std::vector<TileTree>* trees, const std::string& path,
                                          std::map<std::string, render::Rgba>& legend) {
    const PointSpecies species = point_species(cloud, trees, path);
    std::vector<render::Rgba> palette;
    for (const auto& name : species.names) palette.push_back(legend[name] = species_colour(name));
    std::vector<render::Rgba> colours;
    colours.reserve(cloud.size());
    for (int index : species.of_point) colours.push_back(index < 0 ? unknown_species_colour : palette[index]);
    if (std::find(species.of_point.begin(), species.of_point.end(), -1) != species.of_point.end())
        legend["(none)"] = unknown_species_colour;
    return colours;
}

std::vector<render::Rgba> cloud_colours(const PointCloud& cloud, const std::vector<TileTree>* trees, const RenderOptions& options,
                                        const std::string& path, std::map<std::string, render::Rgba>& legend) {
    if (options.colour == "height") return height_colours(cloud);
    if (options.colour == "tree") return tree_colours(cloud, path);
    if (options.colour == "species") return species_colours(cloud, trees, path, legend);
    return {};
}

// A file, or a tile output folder (its points.las, with the species of trees.csv).
Subject load(const std::string& path, const RenderOptions& options, std::map<std::string, render::Rgba>& legend) {
    if (is_tile_output(path)) {
        TileOutput tile = read_tile_output(path);
        std::vector<render::Rgba> colours = cloud_colours(tile.points, &tile.trees, options, path, legend);
        return {std::move(tile.points), path, std::move(colours)};
    }
    const std::string kind = describe_file(path).kind;
    if (kind == "mesh") return {read_mesh(path), path, {}};
    if (kind == "skeleton") return {read_skeleton_ply(path), path, {}};
    PointCloud cloud = read_point_cloud(path);
    std::vector<render::Rgba> colours = cloud_colours(cloud, nullptr, options, path, legend);
    return {std::move(cloud), path, std::move(colours)};
}

std::vector<Eigen::Vector3d> world_points(const PointCloud& cloud) {
    std::vector<Eigen::Vector3d> points;
    points.reserve(cloud.size());
    for (const auto& p : cloud.positions) points.push_back(cloud.origin + p.cast<double>());
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

render::Image draw(const Subject& subject, const RenderOptions& options, const render::View& view, int width, int height) {
    render::Rasterizer r(width, height, view);
    const std::string& colour = options.colour;
    std::visit(
            [&](const auto& thing) {
                using T = std::decay_t<decltype(thing)>;
                if constexpr (std::is_same_v<T, PointCloud>) {
                    if (!subject.point_colours.empty())
                        r.draw_points(world_points(thing), subject.point_colours, 2);
                    else
                        r.draw_points(thing, {40, 90, 40, 255}, 2);
                } else if constexpr (std::is_same_v<T, TriangleMesh>)
                    r.draw_mesh(thing, {150, 110, 70, 255});
                else if (colour == "radius" || colour == "order")
                    draw_coloured_skeleton(r, thing, colour);
                else
                    r.draw_skeleton(thing, {120, 30, 20, 255});
            },
            subject.item);
    return r.image();
}

render::View make_view(const RenderOptions& o, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    if (o.view == "front") return render::View::side(lo, hi, 0, 0);
    if (o.view == "side") return render::View::side(lo, hi, 270, 0);
    if (o.view == "top") return render::View::side(lo, hi, 0, 90);
    return render::View::side(lo, hi, o.azimuth, o.elevation);
}

int panel_width(const RenderOptions& options, const render::View& view) {
    return std::clamp(static_cast<int>(std::lround(options.size * view.aspect())), 64, 4096);
}

// The subjects side by side, all in `view`; each panel takes the subject's shape on the image
// (`view.aspect()`), so it fills the frame.
render::Image draw_panels(const std::vector<Subject>& subjects, const RenderOptions& options, const render::View& view) {
    const int width = panel_width(options, view);
    std::vector<render::Image> panels;
    for (const auto& subject : subjects) panels.push_back(draw(subject, options, view, width, options.size));
    return render::side_by_side(panels);
}

// One turn around the vertical axis through the centre of [lo, hi], starting at --azimuth. Every
// frame frames the cylinder the subject sweeps (its swept radius across, its height seen at
// --elevation up), so the scale is the same in all frames and the subject does not pulse.
std::vector<render::Image> draw_orbit(const std::vector<Subject>& subjects, const RenderOptions& options, const Eigen::Vector3d& lo,
                                      const Eigen::Vector3d& hi) {
    const double radius = swept_radius(subjects, 0.5 * (lo + hi));
    const double elevation = options.elevation * M_PI / 180.0;
    std::vector<render::Image> frames;
    for (int k = 0; k < options.frames; ++k) {
        render::View view = render::View::side(lo, hi, options.azimuth + 360.0 * k / options.frames, options.elevation);
        view.half_width = radius;
        view.half_height = 0.5 * (hi.z() - lo.z()) * std::cos(elevation) + radius * std::abs(std::sin(elevation));
        frames.push_back(draw_panels(subjects, options, view));
    }
    return frames;
}

std::vector<render::LegendEntry> legend_entries(const std::map<std::string, render::Rgba>& legend) {
    std::vector<render::LegendEntry> entries;
    for (const auto& [name, colour] : legend)
        if (name != "(none)") entries.push_back({name, colour});
    if (legend.count("(none)")) entries.push_back({"(none)", legend.at("(none)")});  // last
    return entries;
}

// "ID 7  PINE  22.1 M": the tree's id, species and height when known.
std::string tree_label(const TileTree& tree) {
    std::ostringstream label;
    label << "ID " << tree.id;
    if (!tree.species.empty()) label << "  " << tree.species;
    if (std::isfinite(tree.height_m)) label << "  " << std::fixed << std::setprecision(1) << tree.height_m << " M";
    return label.str();
}

// One panel per tree of the tile output folder `path`, sorted by id, row-major in a grid: each
// tree's points alone, framed by their own box (so every tree fills its panel), with its label
// above. Panels share one shape, the median shape of the trees seen that way.
render::Image draw_contact_sheet(const std::string& path, const RenderOptions& options, std::map<std::string, render::Rgba>& legend,
                                 std::size_t& trees_drawn) {
    if (!is_tile_output(path)) throw Error::input(path, "--contact-sheet needs a tile output folder (trees.csv and points.las)");
    const TileOutput tile = read_tile_output(path);
    std::map<std::string, render::Rgba> tile_legend;  // includes the ground's "(none)"; the sheet shows trees only
    const std::vector<render::Rgba> colours = cloud_colours(tile.points, &tile.trees, options, path, tile_legend);
    const ExtraAttribute& tree_id = *tree_id_attribute(tile.points);
    std::map<int, std::vector<std::size_t>> points_of_tree;
    for (std::size_t i = 0; i < tile.points.size(); ++i) points_of_tree[static_cast<int>(std::lround(tree_id.values[i]))].push_back(i);
    struct Panel {
        const TileTree* tree;
        Subject subject;
        render::View view;
    };
    std::vector<Panel> panels;
    std::vector<double> aspects;
    for (const auto& tree : tile.trees) {
        const auto it = points_of_tree.find(tree.id);
        if (it == points_of_tree.end() || tree.id <= 0) continue;  // a failed tree has no points
        Subject subject{tile.points.subset(it->second), path, {}};
        for (std::size_t i : it->second)
            if (!colours.empty()) subject.point_colours.push_back(colours[i]);
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
        bounds_of(subject.item, lo, hi);
        const render::View view = make_view(options, lo, hi);
        aspects.push_back(view.aspect());
        panels.push_back({&tree, std::move(subject), view});
        if (options.colour == "species")
            legend[tree.species.empty() ? "(none)" : tree.species] =
                    tree.species.empty() ? unknown_species_colour : species_colour(tree.species);
    }
    if (panels.empty()) throw Error::input(path, "no tree with points in the tile output");
    std::nth_element(aspects.begin(), aspects.begin() + aspects.size() / 2, aspects.end());
    const int height = options.size, width = std::clamp(static_cast<int>(std::lround(height * aspects[aspects.size() / 2])), 32, 4096);
    const int scale = std::max(1, height / 100), label_height = render::text_height(scale) + 4 * scale;
    const int columns = options.columns > 0 ? options.columns
                                            : std::max(1, static_cast<int>(std::ceil(std::sqrt(panels.size() * double(height) / width))));
    const int rows = static_cast<int>((panels.size() + columns - 1) / columns);
    const int gap = 2 * scale;
    render::Image sheet(columns * (width + gap) + gap, rows * (height + label_height + gap) + gap, {255, 255, 255, 255});
    for (std::size_t k = 0; k < panels.size(); ++k) {
        const int x0 = gap + static_cast<int>(k % columns) * (width + gap),
                  y0 = gap + static_cast<int>(k / columns) * (height + label_height + gap);
        sheet.fill_rect(x0, y0, x0 + width, y0 + label_height, {235, 235, 235, 255});
        render::draw_text(sheet, x0 + 2 * scale, y0 + 2 * scale, tree_label(*panels[k].tree), scale, {20, 20, 20, 255});
        const render::Image image = draw(panels[k].subject, options, panels[k].view, width, height);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) sheet.set(x0 + x, y0 + label_height + y, image.at(x, y));
    }
    trees_drawn = panels.size();
    return legend.empty() ? sheet : render::with_legend(sheet, legend_entries(legend), scale);
}

int run_render(const RenderOptions& options, const OptionTable& table, const GlobalOptions& global) {
    std::map<std::string, render::Rgba> legend;  // species colouring: name -> colour
    nlohmann::json summary{{"out", options.out}, {"options", table.json()}};
    if (options.contact_sheet) {
        if (options.inputs.size() != 1) throw Error::usage("--contact-sheet takes one tile output folder");
        if (options.view == "orbit") throw Error::usage("--contact-sheet draws still views: --view front, side or top");
        std::size_t trees = 0;
        const render::Image sheet = draw_contact_sheet(options.inputs.front(), options, legend, trees);
        render::write_png(sheet, options.out);
        summary["trees"] = trees;
        summary["width"] = sheet.width;
        summary["height"] = sheet.height;
        if (global.json)
            std::cout << summary.dump(2) << "\n";
        else
            std::cout << "wrote " << options.out << " (" << trees << " trees)\n";
        return 0;
    }
    std::vector<Subject> subjects;
    for (const auto& input : options.inputs) subjects.push_back(load(input, options, legend));
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const auto& subject : subjects) bounds_of(subject.item, lo, hi);
    if (!lo.allFinite() || (lo.array() > hi.array()).any()) throw Error::input(options.inputs.front(), "nothing to draw");
    summary["panels"] = subjects.size();
    const int legend_scale = std::max(2, options.size / 160);
    const auto finish = [&](const render::Image& image) {
        return legend.empty() ? image : render::with_legend(image, legend_entries(legend), legend_scale);
    };
    if (options.view == "orbit") {
        std::vector<render::Image> frames = draw_orbit(subjects, options, lo, hi);
        for (auto& frame : frames) frame = finish(frame);
        render::write_apng(frames, options.frame_ms, options.out);
        summary["frames"] = frames.size();
        summary["width"] = frames.front().width;
        summary["height"] = frames.front().height;
    } else {
        const render::Image image = finish(draw_panels(subjects, options, make_view(options, lo, hi)));
        render::write_png(image, options.out);
        summary["width"] = image.width;
        summary["height"] = image.height;
    }
    if (!legend.empty()) summary["species"] = legend_entries(legend).size() - legend.count("(none)");
    if (global.json)
        std::cout << summary.dump(2) << "\n";
    else
        std::cout << "wrote " << options.out << " (" << subjects.size() << " panel(s)"
                  << (summary.contains("frames") ? ", " + summary["frames"].dump() + " frames" : std::string()) << ")\n";
    return 0;
}

}  // namespace

void add_render_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto options = std::make_shared<RenderOptions>();
    CLI::App* sub = app.add_subcommand("render", "Draw point clouds, meshes, skeletons and tile outputs side by side into a PNG");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("inputs", options->inputs,
                    "Point clouds, meshes (PLY/OBJ/OFF), skeleton PLYs or tile output folders (their points.las)")
            ->required();
    table->add("--out,-o", options->out, "Output PNG")->required();
    table->add("--size", options->size, "Panel height in pixels")->check(CLI::Range(64, 4096));
    table->add("--azimuth", options->azimuth, "View direction around the vertical axis, degrees");
    table->add("--elevation", options->elevation, "View elevation above the horizon, degrees")->check(CLI::Range(-90.0, 90.0));
    table->add("--view", options->view,
               "front (along +y), side (along -x) or top (down), overriding --azimuth/--elevation; orbit: an animated PNG turning once "
               "around the vertical axis from --azimuth at --elevation")
            ->check(CLI::IsMember({"front", "side", "top", "orbit"}));
    table->add("--frames", options->frames, "--view orbit: frames per turn")->check(CLI::Range(2, 360));
    table->add("--frame-ms", options->frame_ms, "--view orbit: milliseconds each frame is shown")->check(CLI::Range(10, 10000));
    table->add("--color", options->colour,
               "plain; clouds: height, tree (treeID) or species (species attribute, or trees.csv of a tile output folder; with a legend); "
               "skeletons: radius or order (branch order)")
            ->check(CLI::IsMember({"plain", "height", "tree", "species", "radius", "order"}));
    table->add_flag("--contact-sheet", options->contact_sheet,
                    "One tile output folder: every tree in its own panel (filling it), sorted by id, labelled with id, species and height");
    table->add("--columns", options->columns, "--contact-sheet: panels per row (0: about square)")->check(CLI::Range(0, 1000));
    sub->callback([options, table, &global, &job] { job = [options, table, &global] { return run_render(*options, *table, global); }; });
}

}  // namespace treelobes::cli
