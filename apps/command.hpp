// How subcommands plug into the `treelobes` CLI. Each apps/cmd_<name>.cpp defines one
// `add_<name>_command` that declares its CLI11 subcommand, binds flags onto the stage's
// options struct and, when selected, stores the job to run in `job`. main.cpp calls the job
// inside one error handler that maps treelobes::Error to exit codes.
#pragma once

#include "core/cloud_io.hpp"
#include "core/error.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace treelobes::cli {

struct GlobalOptions {
    int threads = 0;  // 0 = all cores
    std::string log_level = "info";
    bool json = false;  // machine-readable summary on stdout
};

using Job = std::function<int()>;  // returns the process exit code

// Checks for numeric options: a finite number above (or from) zero. CLI11's PositiveNumber and
// NonNegativeNumber let "nan" through and quote the whole double range in their message.
inline CLI::Validator finite_number(bool zero_allowed) {
    return CLI::Validator(
            [zero_allowed](std::string& text) -> std::string {
                double value = 0;
                if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
                if (!std::isfinite(value) || (zero_allowed ? value < 0 : value <= 0))
                    return std::string("must be a finite number ") + (zero_allowed ? ">= 0" : "> 0") + ", got " + text;
                return {};
            },
            zero_allowed ? "NUMBER >= 0" : "NUMBER > 0");
}
inline const CLI::Validator PositiveNumber = finite_number(false);
inline const CLI::Validator NonNegativeNumber = finite_number(true);

// `--bounds minx,miny,minz,maxx,maxy,maxz` (3-D) or `minx,miny,maxx,maxy` (2-D: any z), in the
// file's original coordinates. Throws Error(Usage) naming the flag.
inline Box3d parse_bounds(const std::string& text) {
    std::vector<double> v;
    std::stringstream in(text);
    for (std::string item; std::getline(in, item, ',');) {
        double value = 0;
        if (!CLI::detail::lexical_cast(item, value) || !std::isfinite(value))
            throw Error::usage("--bounds: '" + item + "' is not a finite number");
        v.push_back(value);
    }
    constexpr double inf = std::numeric_limits<double>::infinity();
    Box3d box;
    if (v.size() == 6)
        box = {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
    else if (v.size() == 4)
        box = {{v[0], v[1], -inf}, {v[2], v[3], inf}};
    else
        throw Error::usage("--bounds takes minx,miny,minz,maxx,maxy,maxz or minx,miny,maxx,maxy, got '" + text + "'");
    if ((box.min.array() > box.max.array()).any()) throw Error::usage("--bounds: a minimum exceeds its maximum in '" + text + "'");
    return box;
}

// Every subcommand above, in the order of `treelobes --help`.
void add_commands(CLI::App& app, const GlobalOptions& global, Job& job);

void add_info_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_convert_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_multires_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_reconstruct_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_eval_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_encode_commands(CLI::App& app, const GlobalOptions& global, Job& job);
void add_render_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_synth_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_classify_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_lobes_commands(CLI::App& app, const GlobalOptions& global, Job& job);
void add_export_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_rebuild_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_compare_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_tile_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_batch_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_merge_command(CLI::App& app, const GlobalOptions& global, Job& job);
void add_retile_command(CLI::App& app, const GlobalOptions& global, Job& job);

}  // namespace treelobes::cli
