// `treelobes merge DIR... --out OUT`: the results of tiles and batches (shards) joined into one
// trees.csv, trees.geojson, crowns.geojson, survey.forest and summary.json, sorted by the global tree id so that
// the bytes do not depend on the order of the folders or on how the tiles were sharded.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "survey/merge.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

namespace fs = std::filesystem;

namespace treelobes::cli {

namespace {

struct MergeCliOptions {
    std::vector<std::string> inputs;
    std::string out;
};

int run_merge(const MergeCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    std::vector<fs::path> dirs(o.inputs.begin(), o.inputs.end());
    const survey::TileFolders folders = survey::find_tile_folders(dirs);
    for (const std::string& name : folders.incomplete) log_warn("tile " + name + " is not finished (no completion marker): left out");
    const survey::MergedSurvey merged = survey::merge_tiles(folders);
    if (!merged.trees_at_buffer_edge.empty())
        log_warn(std::to_string(merged.trees_at_buffer_edge.size()) + " trees reached their tile's buffer edge and may be cut there (" +
                 merged.trees_at_buffer_edge.front() + (merged.trees_at_buffer_edge.size() > 1 ? ", ..." : "") +
                 "; all in summary.json, trees_at_buffer_edge): run those tiles again with a wider --buffer");
    for (const std::string& duplicate : merged.duplicated_ids)
        log_warn("tree " + duplicate + ": one tree modelled by two tiles; run the tiles with --buffer so that each tree belongs to one");
    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (!fs::is_directory(o.out)) throw Error::usage("--out " + o.out + ": cannot create the output folder");
    const fs::path out(o.out);
    write_file_atomically(out / "trees.csv", merged.trees_csv);
    write_file_atomically(out / "trees.geojson", merged.trees_geojson);
    write_file_atomically(out / "crowns.geojson", merged.crowns_geojson);
    write_file_atomically(out / "survey.forest", std::string(merged.forest.begin(), merged.forest.end()));
    write_file_atomically(out / "summary.json", merged.summary_json);
    if (merged.failures_jsonl.empty())
        fs::remove(out / "failures.jsonl", ec);
    else
        write_file_atomically(out / "failures.jsonl", merged.failures_jsonl);
    const bool partial = !merged.failures_jsonl.empty() || !folders.incomplete.empty();
    if (global.json) {
        // summary.json holds no paths (the same survey merges into the same bytes wherever it goes), so
        // merge's own flag, --out, is reported beside the tiles' options on stdout only.
        nlohmann::json summary = nlohmann::json::parse(merged.summary_json);
        summary["merge_options"] = table.json();
        std::cout << summary.dump(2) << "\n";
    } else {
        std::printf("merge: %zu tiles, %zu trees -> %s (trees.csv, trees.geojson, crowns.geojson, survey.forest, summary.json)%s\n",
                    merged.tiles, merged.trees, o.out.c_str(),
                    partial ? "; some tiles failed or are unfinished (failures.jsonl, summary.json: tiles_incomplete)" : "");
    }
    return partial ? static_cast<int>(ExitCode::PartialFailure) : 0;
}

}  // namespace

void add_merge_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto o = std::make_shared<MergeCliOptions>();
    CLI::App* sub = app.add_subcommand(
            "merge",
            "Join tile and batch outputs into one trees.csv, trees.geojson, crowns.geojson, survey.forest and summary.json, "
            "order-independent (docs/survey.md)");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("dirs", o->inputs, "Tile output folders or batch output folders (their finished tiles)")->required();
    table->add("--out", o->out, "Output folder")->required();
    sub->callback([o, table, &global, &job] { job = [o, table, &global] { return run_merge(*o, *table, global); }; });
}

}  // namespace treelobes::cli
