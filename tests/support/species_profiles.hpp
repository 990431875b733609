// The species profiles of config/species.yaml, loaded once per test program.
#pragma once

#include "config/species_profile.hpp"

#include <vector>

namespace treelobes::test {

inline const std::vector<SpeciesProfile>& species_profiles() {
    static const std::vector<SpeciesProfile> profiles = load_species_profiles(default_species_file());
    return profiles;
}

}  // namespace treelobes::test
