// What the commands that run the skeleton reconstruction share (`reconstruct`, `lobes`): the
// species flags (β, γ, f_s from config/species.yaml, explicit values on top) and the ground mode.
#pragma once

#include "apps/option_table.hpp"
#include "reconstruct/reconstruct_tree.hpp"

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

namespace treelobes::cli {

struct SpeciesFlags {
    std::string species;                    // canonical name after apply_species_flags()
    std::optional<double> beta, gamma, fs;  // explicit values override the species'
    std::string ground = "auto";
};

// Adds --species, --beta, --gamma, --fs (with `fs_help`) and --ground to `table`. The summary
// reports the canonical species (null when none) and the β, γ, f_s that `stage` ends up with.
void add_species_flags(OptionTable& table, SpeciesFlags& flags, const std::string& fs_help, const ReconstructOptions& stage);

// Species parameters first, explicit --beta/--gamma/--fs on top, then the ground mode.
// Unknown species or a broken species file: Error (usage/config).
void apply_species_flags(SpeciesFlags& flags, ReconstructOptions& stage);

}  // namespace treelobes::cli
