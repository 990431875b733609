// The species library (config/species.yaml): per-species reconstruction parameters of
// Livny et al. 2011, Table 1 (beta, gamma, f_s), growth profiles for synthesis, branchlet patch
// profiles (Livny et al. 2011, Appendix A) and ranges of natural variation. Loaded and validated by
// config/species_library.cpp with yaml-cpp; unknown keys and out-of-range values throw
// Error(Usage) naming the file, the species and the key.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace treelobes {

// Livny et al. 2011, §4.1-4.2: edge weight ||u-v||^beta, allometry d(u) = d_root (l(u)/l(root))^gamma,
// lobe-confidence diameter d'(u) = f_s d(u).
struct ReconstructionParameters {
    double beta = 1.0;
    double gamma = 1.5;
    double fs = 1.0;
};

struct SpeciesProfile;  // full profile (growth, patches, variation): config/species_profile.hpp

struct SpeciesEntry {
    std::string name;  // canonical key, e.g. "pine", "ficus_virens"
    std::string display_name;
    int id = 0;  // stable 1-based id used in labels and LAS `species`
    ReconstructionParameters reconstruction;
};

// Path of the species.yaml shipped with the source tree (compiled in), overridable with the
// environment variable TREELOBES_SPECIES.
std::filesystem::path default_species_file();

// Names, ids and reconstruction parameters of every species in a file.
std::vector<SpeciesEntry> load_species_entries(const std::filesystem::path& file);

// Looks a species up by name (case-insensitive; spaces and '-' match '_'). Throws Error(Usage)
// listing the known names when it is not there.
SpeciesEntry find_species(const std::vector<SpeciesEntry>& entries, const std::string& name);

}  // namespace treelobes
