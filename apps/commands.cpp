#include "apps/command.hpp"

namespace treelobes::cli {

void add_commands(CLI::App& app, const GlobalOptions& global, Job& job) {
    add_info_command(app, global, job);
    add_convert_command(app, global, job);
    add_multires_command(app, global, job);
    add_reconstruct_command(app, global, job);
    add_eval_command(app, global, job);
    add_encode_commands(app, global, job);
    add_render_command(app, global, job);
    add_synth_command(app, global, job);
    add_classify_command(app, global, job);
    add_lobes_commands(app, global, job);
    add_export_command(app, global, job);
    add_rebuild_command(app, global, job);
    add_compare_command(app, global, job);
    add_tile_command(app, global, job);
    add_batch_command(app, global, job);
    add_merge_command(app, global, job);
    add_retile_command(app, global, job);
}

}  // namespace treelobes::cli
