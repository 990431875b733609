#include "apps/reconstruction_flags.hpp"

#include "apps/command.hpp"
#include "config/species_library.hpp"

namespace treelobes::cli {

void add_species_flags(OptionTable& table, SpeciesFlags& flags, const std::string& fs_help, const ReconstructOptions& stage) {
    table.add("--species", flags.species, "Species from config/species.yaml: sets beta, gamma and f_s");
    table.add("--beta", flags.beta, "Edge weight exponent ||u-v||^beta (default 1.5, or the species')")->check(cli::PositiveNumber);
    table.add("--gamma", flags.gamma, "Allometry exponent of Eq. 1 (default 1.5, or the species')")->check(cli::PositiveNumber);
    table.add("--fs", flags.fs, fs_help)->check(CLI::Range(0.01, 1.0));
    table.add("--ground", flags.ground, "Ground points: auto (remove a detected ground plane), remove, keep")
            ->check(CLI::IsMember({"auto", "remove", "keep"}));
    table.report_as("--species", [&flags] { return flags.species.empty() ? nlohmann::json() : nlohmann::json(flags.species); });
    table.report_as("--beta", [&stage] { return stage.skeleton.beta; });
    table.report_as("--gamma", [&stage] { return stage.allometry.gamma; });
    table.report_as("--fs", [&stage] { return stage.allometry.fs; });
}

void apply_species_flags(SpeciesFlags& flags, ReconstructOptions& stage) {
    if (!flags.species.empty()) {
        const SpeciesEntry entry = find_species(load_species_entries(default_species_file()), flags.species);
        flags.species = entry.name;
        stage.skeleton.beta = entry.reconstruction.beta;
        stage.allometry.gamma = entry.reconstruction.gamma;
        stage.allometry.fs = entry.reconstruction.fs;
    }
    if (flags.beta) stage.skeleton.beta = *flags.beta;
    if (flags.gamma) stage.allometry.gamma = *flags.gamma;
    if (flags.fs) stage.allometry.fs = *flags.fs;
    stage.preprocess.ground = parse_ground_mode(flags.ground);
}

}  // namespace treelobes::cli
