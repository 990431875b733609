// `treelobes compare A B`: how close mesh B is to mesh A, with the fidelity figures that
// `treelobes rebuild` reports for its rebuilt tree (apps/mesh_fidelity.hpp): Metro-style surface
// distances, silhouette and crown-outline IoU from the front, the side and the top, leaf areas.
// Compares a rebuilt tree with another tool's, two levels of detail, or a tree with itself
// re-leafed (docs/rebuild.md: what a silhouette IoU can reach).
#include "apps/command.hpp"
#include "apps/mesh_fidelity.hpp"
#include "apps/option_table.hpp"
#include "apps/summary_values.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/mesh_io.hpp"
#include "core/version.hpp"
#include "render/image.hpp"
#include "synth/mesh_labels.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <memory>

namespace treelobes::cli {

namespace {

using json = nlohmann::json;

struct CompareCliOptions {
    std::string first, second, png;
    MeshFidelityOptions fidelity;
};

struct LabelledMesh {
    NamedMesh named;
    synth::MeshLabelReport labels;
};

LabelledMesh read_labelled(const std::string& path) {
    log_info("compare: reading " + path);
    LabelledMesh m{read_named_mesh(path), {}};
    if (m.named.mesh.faces.empty()) throw Error::input(path, "the mesh has no triangles");
    const auto [lo, hi] = world_bounds(m.named.mesh);
    if (!((hi - lo).norm() > 0)) throw Error::input(path, "the mesh has no extent (every vertex at one place)");
    if (!(m.named.mesh.area() > 0)) throw Error::input(path, "every triangle has zero area: no surface to compare");
    synth::label_faces(m.named, {}, &m.labels);
    return m;
}

json mesh_json(const std::string& path, const LabelledMesh& m) {
    return {{"path", path},
            {"format", m.named.report.format},
            {"triangles", m.named.mesh.faces.size()},
            {"leaf_area_m2", rounded(m.labels.leaf_area, 3)},
            {"wood_area_m2", rounded(m.labels.wood_area, 3)}};
}

void print_comparison(const json& r) {
    const json& f = r["fidelity"];
    std::printf("%s (A) against %s (B)\n", r["a"]["path"].get<std::string>().c_str(), r["b"]["path"].get<std::string>().c_str());
    std::printf("  triangles %zu / %zu, leaf area %.1f / %.1f m^2\n", r["a"]["triangles"].get<std::size_t>(),
                r["b"]["triangles"].get<std::size_t>(), r["a"]["leaf_area_m2"].get<double>(), r["b"]["leaf_area_m2"].get<double>());
    std::printf("  distance mean %.3f m (%.2f %% of A's diagonal), p95 %.3f m, Hausdorff %.3f m\n", f["symmetric"]["mean"].get<double>(),
                100 * f["symmetric"]["mean_of_diagonal"].get<double>(), f["symmetric"]["p95"].get<double>(),
                f["symmetric"]["max"].get<double>());
    print_silhouettes(f);
}

int run_compare(const CompareCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    const LabelledMesh a = read_labelled(o.first), b = read_labelled(o.second);
    log_info("compare: distances and silhouettes");
    render::Image crowns;
    json fidelity = mesh_fidelity(a.named.mesh, b.named.mesh, o.fidelity, o.png.empty() ? nullptr : &crowns);
    if (!o.png.empty()) render::write_png(crowns, o.png);
    fidelity["leaf_area_ratio"] = a.labels.leaf_area > 0 ? json(rounded(b.labels.leaf_area / a.labels.leaf_area, 4)) : json();
    const json report = {{"treelobes", kVersion},      {"command", "compare"},        {"options", table.json()},
                         {"a", mesh_json(o.first, a)}, {"b", mesh_json(o.second, b)}, {"fidelity", fidelity}};
    if (global.json)
        std::cout << report.dump(2) << "\n";
    else
        print_comparison(report);
    return 0;
}

}  // namespace

void add_compare_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto o = std::make_shared<CompareCliOptions>();
    CLI::App* sub = app.add_subcommand("compare",
                                       "How close mesh B is to mesh A: surface distances, silhouette and crown-outline IoU (front, side, "
                                       "top), leaf areas");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("a", o->first, "Reference mesh (.obj, .glb, .ply, .off, .stl); distances are also given in fractions of its diagonal")
            ->required();
    sub->add_option("b", o->second, "Mesh compared with it")->required();
    table->add("--compare-samples", o->fidelity.samples, "Samples per surface for the distances")->check(CLI::Range(1000, 10000000));
    table->add("--seed", o->fidelity.seed, "Random seed of the surface samples");
    table->add("--png", o->png, "Also draw the crown outlines of both meshes (front, side, top; both / A only / B only) to this PNG");
    table->add("--silhouette-px", o->fidelity.silhouette_px, "Side of the square silhouette masks, pixels")->check(CLI::Range(32, 4096));
    table->add("--crown-closing-px", o->fidelity.crown_closing_px,
               "Crown outline: gaps narrower than this (pixels of the mask) are closed before holes are filled")
            ->check(CLI::Range(0, 256));
    sub->callback([o, table, &global, &job] { job = [o, table, &global] { return run_compare(*o, *table, global); }; });
}

}  // namespace treelobes::cli
