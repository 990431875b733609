// `treelobes retile INPUT... --size METRES --out DIR`: big or irregular point clouds cut into
// square LAS 1.4 tiles named by their lower-left corner, so a survey delivered as a few huge
// files can be run by `treelobes batch` (docs/survey.md).
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "core/cloud_header.hpp"
#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "survey/retile.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

namespace fs = std::filesystem;

namespace treelobes::cli {

namespace {

struct RetileCliOptions {
    std::vector<std::string> inputs;
    std::string out;
    std::string max_memory;
    survey::RetileOptions retile;
};

int run_retile(const RetileCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    const double budget = o.max_memory.empty() ? default_memory_budget_bytes() : parse_memory_size(o.max_memory);
    std::size_t points = 0;
    for (const std::string& input : o.inputs) points += header_point_count(input);
    if (const auto refusal = memory_refusal(points, kRetileBytesPerPoint, budget))
        throw Error::input(o.inputs.front(), "retile: the inputs' " + *refusal);
    const std::vector<fs::path> inputs(o.inputs.begin(), o.inputs.end());
    const auto tiles = survey::retile(inputs, o.retile, o.out);
    nlohmann::json listed = nlohmann::json::array();
    std::size_t written_points = 0;
    for (const auto& tile : tiles) {
        listed.push_back({{"path", tile.path.string()}, {"x", tile.x}, {"y", tile.y}, {"points", tile.points}});
        written_points += tile.points;
    }
    if (global.json) {
        const nlohmann::json summary = {{"command", "retile"},   {"inputs", o.inputs},       {"options", table.json()},
                                        {"size", o.retile.size}, {"points", written_points}, {"tiles", listed}};
        std::cout << summary.dump(2) << "\n";
    } else {
        std::printf("retile: %zu inputs, %zu points -> %zu tiles of %g m in %s\n", o.inputs.size(), written_points, tiles.size(),
                    o.retile.size, o.out.c_str());
    }
    return 0;
}

}  // namespace

void add_retile_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto o = std::make_shared<RetileCliOptions>();
    CLI::App* sub = app.add_subcommand("retile",
                                       "Cut point clouds into square LAS 1.4 tiles (CRS, scale and offset kept), named by their "
                                       "lower-left corner, for `treelobes batch` (docs/survey.md)");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("inputs", o->inputs, "Point clouds (LAS, PLY, PCD, XYZ), one CRS")->required()->check(CLI::ExistingFile);
    table->add("--size", o->retile.size, "Tile side, metres")->required()->check(PositiveNumber);
    table->add("--out", o->out, "Output folder")->required();
    table->add("--prefix", o->retile.prefix, "File name prefix: <prefix>_<x>_<y>.las");
    table->add("--max-memory", o->max_memory,
               "Refuse inputs whose header point counts need more memory than this (e.g. 8G; default: "
               "half of the RAM)");
    sub->callback([o, table, &global, &job] { job = [o, table, &global] { return run_retile(*o, *table, global); }; });
}

}  // namespace treelobes::cli
