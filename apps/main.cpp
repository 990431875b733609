// treelobes — laser scans of trees to compact, renderable tree models.
// Parses the command line, runs the selected subcommand and maps errors to exit codes
// (0 ok, 1 usage/config, 2 invalid input, 3 partial failure, 4 internal).
#include "apps/command.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/version.hpp"

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <iostream>
#include <memory>
#include <new>

using namespace treelobes;

namespace {

void add_global_flags(CLI::App& app, cli::GlobalOptions& global) {
    app.set_version_flag("--version", std::string("treelobes ") + kVersion);
    app.add_option("--threads", global.threads, "Worker threads (0 = all cores)")->check(cli::NonNegativeNumber);
    app.add_option("--log-level", global.log_level, "Log level on stderr: error, warn, info, debug")
            ->check(CLI::IsMember({"error", "warn", "info", "debug"}));
    app.add_flag("--json", global.json, "Print the summary as JSON on stdout");
}

int run(int argc, char** argv) {
    CLI::App app{"treelobes: laser scans of trees to compact, renderable tree models"};
    app.require_subcommand(1);
    app.fallthrough();  // global flags are accepted after the subcommand too
    cli::GlobalOptions global;
    add_global_flags(app, global);

    cli::Job job;
    cli::add_commands(app, global, job);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);  // prints help/version or the usage error
        return code == 0 ? 0 : static_cast<int>(ExitCode::Usage);
    }
    set_log_level(parse_log_level(global.log_level));
    // --threads caps every TBB parallel loop of the stages for the whole run.
    std::unique_ptr<tbb::global_control> thread_limit;
    if (global.threads > 0)
        thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                             static_cast<std::size_t>(global.threads));
    return job ? job() : static_cast<int>(ExitCode::Usage);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const Error& e) {
        std::cerr << "treelobes: error: " << e.what() << "\n";
        return static_cast<int>(e.code());
    } catch (const std::bad_alloc&) {
        std::cerr << "treelobes: error: out of memory\n";
        return static_cast<int>(ExitCode::Internal);
    } catch (const std::exception& e) {
        std::cerr << "treelobes: internal error: " << e.what() << "\n";
        return static_cast<int>(ExitCode::Internal);
    }
}
