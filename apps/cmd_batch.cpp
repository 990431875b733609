// `treelobes batch LIST|DIR|GLOB --out DIR [--shard i/n] [tile options]`: the tile pipeline over
// many tiles, one output folder per tile, in a stable order (sorted paths; shard i of n takes
// every n-th), so that Slurm array tasks or GNU parallel jobs split a survey without talking to
// each other (docs/survey.md). Each tile runs in this process through the `tile` subcommand
// itself, with its own error boundary: a bad tile is listed in failures.jsonl and the batch goes
// on. A tile's folder is finished when its completion marker exists (written last, atomically);
// a re-run skips finished tiles and redoes partial ones from scratch. With --buffer, a tile's
// neighbours are the other tiles of the batch (all shards') unless --neighbours names others.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "apps/summary_values.hpp"
#include "core/atomic_file.hpp"
#include "core/cloud_header.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory_limit.hpp"
#include "core/version.hpp"
#include "segment/segment_trees.hpp"
#include "segment/terrain.hpp"
#include "survey/completion.hpp"
#include "survey/tile_list.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <new>
#include <optional>
#include <sstream>

namespace fs = std::filesystem;

namespace treelobes::cli {

namespace {

using nlohmann::json;

struct BatchCliOptions {
    std::string source;
    std::string out;
    std::string shard;
    std::string max_memory;
    bool overwrite = false;
    std::vector<std::string> tile_arguments;  // passed on to every `tile` run
};

bool has_option(const std::vector<std::string>& arguments, const std::string& name) {
    return std::any_of(arguments.begin(), arguments.end(), [&](const std::string& a) { return a == name || a.rfind(name + "=", 0) == 0; });
}

// The tile options of every run: the user's, and with --buffer the batch's tiles as neighbours.
std::vector<std::string> tile_arguments_of(const BatchCliOptions& o) {
    std::vector<std::string> arguments = o.tile_arguments;
    if (has_option(arguments, "--buffer") && !has_option(arguments, "--neighbours")) {
        arguments.push_back("--neighbours");
        arguments.push_back(o.source);
    }
    return arguments;
}

// Does `--mode tls` (or --mode=tls) stand among the tile options?
bool terrestrial_mode(const std::vector<std::string>& arguments) {
    for (std::size_t i = 0; i < arguments.size(); ++i)
        if (arguments[i] == "--mode=tls" || (arguments[i] == "--mode" && i + 1 < arguments.size() && arguments[i + 1] == "tls"))
            return true;
    return false;
}

struct SurveySpacing {
    float metres = 0.0f;
    fs::path tile;  // the tile it was measured on
};

// The tile whose header states the median point density: the survey's typical tile. Every shard
// picks the same one from the same sorted list. Tiles without header bounds (not LAS) count as
// of unknown density; when none has bounds, the first tile.
fs::path typical_tile(const std::vector<fs::path>& tiles) {
    std::vector<std::pair<double, fs::path>> densities;
    for (const fs::path& tile : tiles) {
        try {
            const std::optional<Box3d> bounds = header_bounds(tile);
            if (!bounds) continue;
            const double area = (bounds->max.x() - bounds->min.x()) * (bounds->max.y() - bounds->min.y());
            if (area > 0.0) densities.emplace_back(static_cast<double>(header_point_count(tile)) / area, tile);
        } catch (const Error&) {
            // a tile without a readable header fails in its own run
        }
    }
    if (densities.empty()) return tiles.front();
    std::sort(densities.begin(), densities.end());
    return densities[densities.size() / 2].second;
}

// One return spacing for every tile's canopy height model (docs/survey.md), unless the tile
// options give one or take no airborne segmentation. Tiles that estimate their own draw slightly
// different CHMs, and the crowns at their edges differ from the uncut survey's: lidR's
// MixedConifer cut into 45 m tiles with a 7 m buffer kept 180 of its 215 trees as in the uncut
// run, and all 215 with one spacing. nullopt when the typical tile cannot be read, holds no
// vegetation or is as dense as a terrestrial scan (whose segmentation has no CHM): each tile then
// estimates its own.
std::optional<SurveySpacing> survey_return_spacing(const std::vector<fs::path>& tiles, const std::vector<std::string>& arguments,
                                                   double memory_budget) {
    if (has_option(arguments, "--return-spacing") || has_option(arguments, "--use-input-segmentation") || terrestrial_mode(arguments))
        return std::nullopt;
    const fs::path tile = typical_tile(tiles);
    log_info("measuring the survey's return spacing on " + tile.string());
    try {
        // The same refusal as the tile's own run: a tile beyond the budget is not read here either.
        if (const auto refusal = memory_refusal(header_point_count(tile), kTileBytesPerPoint, memory_budget))
            throw Error::input(tile.string(), *refusal);
        const PointCloud cloud = read_point_cloud(tile);
        const float spacing = vegetation_return_spacing(cloud, analyse_terrain(cloud, {}), {});
        const float terrestrial_spacing = 1.0f / std::sqrt(SegmentOptions{}.terrestrial_density);
        if (spacing > terrestrial_spacing) return SurveySpacing{spacing, tile};
    } catch (const std::exception& e) {  // treelobes::Error for bad input or a tile beyond the budget, std::bad_alloc
        log_warn("the survey's return spacing could not be measured on " + tile.string() + " (" + e.what() +
                 "): each tile estimates its own");
    }
    return std::nullopt;
}

// The memory budget is the tile's own check (before it reads anything); not part of the key.
std::vector<std::string> with_memory_budget(std::vector<std::string> arguments, const BatchCliOptions& o) {
    if (!o.max_memory.empty()) {
        arguments.push_back("--max-memory");
        arguments.push_back(o.max_memory);
    }
    return arguments;
}

// Parses `tile <input> --out <dir> <tile arguments>` the way the CLI does and returns its job.
// The tile's global options: this process's threads, and its summary as JSON (swallowed below)
// instead of the human lines, so the batch keeps one display.
Job tile_job(CLI::App& app, const GlobalOptions& tile_global, const fs::path& input, const fs::path& dir,
             const std::vector<std::string>& tile_arguments) {
    Job job;
    add_tile_command(app, tile_global, job);
    std::vector<std::string> args{"tile", input.string(), "--out", dir.string()};
    args.insert(args.end(), tile_arguments.begin(), tile_arguments.end());
    std::reverse(args.begin(), args.end());  // CLI11 takes the arguments last first
    try {
        app.parse(args);
    } catch (const CLI::ParseError& e) {
        throw Error::usage(std::string("tile options of the batch: ") + e.what());
    }
    return job;
}

// Runs one tile in this process with its stdout swallowed and info logs quiet; returns its exit
// code. Errors propagate to the caller's boundary.
int run_one_tile(const fs::path& input, const fs::path& dir, const std::vector<std::string>& tile_arguments, const GlobalOptions& global) {
    GlobalOptions tile_global = global;
    tile_global.json = true;
    CLI::App app;
    const Job job = tile_job(app, tile_global, input, dir, tile_arguments);
    std::ostringstream swallowed;
    std::streambuf* const stdout_buffer = std::cout.rdbuf(swallowed.rdbuf());
    const LogLevel level = log_level();
    if (level > LogLevel::Warn) set_log_level(LogLevel::Warn);
    struct Restore {
        std::streambuf* buffer;
        LogLevel level;
        ~Restore() {
            std::cout.rdbuf(buffer);
            set_log_level(level);
        }
    } restore{stdout_buffer, level};
    return job();
}

// The key a finished tile's marker holds: what made its outputs.
std::string completion_key(const fs::path& input, const std::vector<std::string>& tile_arguments) {
    json key = {{"input", fs::absolute(input).lexically_normal().string()}, {"tile_arguments", tile_arguments}, {"treelobes", kVersion}};
    return key.dump();
}

std::string failures_name(const BatchCliOptions& o, const survey::Shard& shard) {
    if (o.shard.empty()) return "failures.jsonl";
    return "failures.shard" + std::to_string(shard.index) + "of" + std::to_string(shard.count) + ".jsonl";
}

void write_failures(const fs::path& path, const std::vector<json>& failures) {
    if (failures.empty()) {
        std::error_code ec;
        fs::remove(path, ec);  // the failures of an earlier run no longer hold
        return;
    }
    std::string lines;
    for (const json& failure : failures) lines += failure.dump() + "\n";
    write_file_atomically(path, lines);
}

struct TileResult {
    int exit_code = 0;
    std::string reason;  // of a failed tile
};

// One tile inside its error boundary (the tile refuses itself when its header says it would not fit).
TileResult process_tile(const fs::path& input, const fs::path& dir, const std::vector<std::string>& arguments,
                        const GlobalOptions& global) {
    try {
        return {run_one_tile(input, dir, arguments, global), {}};
    } catch (const Error& e) {
        return {static_cast<int>(e.code()), e.what()};
    } catch (const std::bad_alloc&) {
        return {static_cast<int>(ExitCode::Internal), "out of memory: retile with a smaller --size or lower --max-memory"};
    } catch (const std::exception& e) {
        return {static_cast<int>(ExitCode::Internal), std::string("internal error: ") + e.what()};
    }
}

int run_batch(BatchCliOptions& o, const OptionTable& table, const GlobalOptions& global) {
    const survey::Shard shard = o.shard.empty() ? survey::Shard{} : survey::parse_shard(o.shard);
    // A bad size is a usage error before any tile runs.
    const double memory_budget = o.max_memory.empty() ? default_memory_budget_bytes() : parse_memory_size(o.max_memory);
    std::vector<std::string> key_arguments = tile_arguments_of(o);
    const std::vector<fs::path> all = survey::list_tiles(o.source);
    const std::optional<SurveySpacing> spacing = survey_return_spacing(all, key_arguments, memory_budget);
    if (spacing) {
        char metres[32];
        std::snprintf(metres, sizeof metres, "%.3f", static_cast<double>(spacing->metres));
        key_arguments.insert(key_arguments.end(), {"--return-spacing", metres});
        log_info(std::string("every tile's CHM from a return spacing of ") + metres + " m, measured on " + spacing->tile.string());
    }
    const std::vector<std::string> run_arguments = with_memory_budget(key_arguments, o);
    const std::vector<fs::path> tiles = survey::shard_tiles(all, shard);
    {
        CLI::App check;  // tile options are checked once, before any tile runs
        tile_job(check, global, all.front(), fs::path(o.out) / survey::tile_name(all.front()), run_arguments);
    }
    std::error_code ec;
    fs::create_directories(o.out, ec);
    if (!fs::is_directory(o.out)) throw Error::usage("--out " + o.out + ": cannot create the output folder");
    const fs::path failures_path = fs::path(o.out) / failures_name(o, shard);

    std::size_t done = 0, skipped = 0, with_tree_failures = 0;
    std::vector<json> failures;
    Progress progress("tiles", tiles.size());
    for (const fs::path& input : tiles) {
        const std::string name = survey::tile_name(input);
        const fs::path dir = fs::path(o.out) / name;
        const std::string key = completion_key(input, key_arguments);
        if (!o.overwrite && survey::is_complete(dir, key)) {
            ++skipped;
            progress.advance();
            continue;
        }
        fs::remove_all(dir, ec);  // a partial folder (killed, failed, other options) is redone from scratch
        const TileResult result = process_tile(input, dir, run_arguments, global);
        if (result.exit_code == 0 || result.exit_code == static_cast<int>(ExitCode::PartialFailure)) {
            survey::mark_complete(dir, key, result.exit_code);
            ++done;
            if (result.exit_code != 0) ++with_tree_failures;
        } else {
            failures.push_back({{"tile", name}, {"input", input.string()}, {"reason", result.reason}, {"exit_code", result.exit_code}});
            write_failures(failures_path, failures);
            log_warn(name + ": " + result.reason);
        }
        progress.advance();
    }
    progress.finish();
    write_failures(failures_path, failures);

    const json summary = {
            {"treelobes", kVersion},
            {"command", "batch"},
            {"source", o.source},
            {"out", o.out},
            {"options", table.json()},
            {"shard", o.shard.empty() ? json(nullptr) : json(o.shard)},
            {"tiles_total", all.size()},
            {"tiles", tiles.size()},
            {"tiles_done", done},
            {"tiles_skipped", skipped},
            {"tiles_failed", failures.size()},
            {"tiles_with_tree_failures", with_tree_failures},
            {"return_spacing",
             spacing ? json{{"metres", rounded(spacing->metres, 3)}, {"measured_on", spacing->tile.string()}} : json(nullptr)},
            {"failures", failures.empty() ? json(nullptr) : json(failures_path.string())},
            {"peak_memory_mb", rounded(peak_memory_mb(), 1)}};
    if (global.json) {
        std::cout << summary.dump(2) << "\n";
    } else {
        std::printf("batch %s: %zu of %zu tiles%s: %zu done, %zu finished earlier (skipped), %zu failed%s\n", o.source.c_str(),
                    tiles.size(), all.size(), o.shard.empty() ? "" : (" (shard " + o.shard + ")").c_str(), done, skipped, failures.size(),
                    failures.empty() ? "" : (" (" + failures_path.string() + ")").c_str());
    }
    return failures.empty() ? 0 : static_cast<int>(ExitCode::PartialFailure);
}

}  // namespace

void add_batch_command(CLI::App& app, const GlobalOptions& global, Job& job) {
    auto o = std::make_shared<BatchCliOptions>();
    CLI::App* sub = app.add_subcommand(
            "batch",
            "The tile pipeline over many tiles: one folder per tile, resumable, shardable for Slurm arrays and GNU parallel "
            "(docs/survey.md). Options after the source that batch does not know are passed to every `tile` run");
    auto table = std::make_shared<OptionTable>(sub);
    sub->add_option("source", o->source, "The tiles: a folder, a quoted pattern (\"tiles/*.las\") or a list file (one path per line)")
            ->required();
    table->add("--out", o->out, "Output folder: one subfolder per tile, named after the tile's file")->required();
    table->add("--shard", o->shard, "Run only shard i of n (0 <= i < n): every n-th tile of the sorted list, starting at i");
    table->add("--max-memory", o->max_memory,
               "Refuse a tile whose header point count needs more memory than this (e.g. 8G; default: half of the RAM); passed to every "
               "`tile` run");
    table->add_flag("--overwrite", o->overwrite, "Redo tiles that an earlier run finished");
    sub->allow_extras();
    sub->fallthrough(false);  // unknown options are the tile's, not the main command's
    sub->callback([o, table, sub, &global, &job] {
        o->tile_arguments = sub->remaining();
        for (const std::string& argument : o->tile_arguments)
            if (argument == "--json" || argument.rfind("--threads", 0) == 0 || argument.rfind("--log-level", 0) == 0)
                throw CLI::ValidationError(argument, "a global flag goes before the subcommand: treelobes " + argument + " batch ...");
        job = [o, table, &global] { return run_batch(*o, *table, global); };
    });
}

}  // namespace treelobes::cli
