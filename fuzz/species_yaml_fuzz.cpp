// The species library loader (config/species_library.cpp): YAML structure, keys, ranges.
#include "config/species_library.hpp"
#include "config/species_profile.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const auto path = treelobes::fuzz::input_file(treelobes::fuzz::as_text(data, size), "yaml");
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::load_species_profiles(path); });
    treelobes::fuzz::expect_only_input_errors([&] { treelobes::load_species_entries(path); });
    return 0;
}
