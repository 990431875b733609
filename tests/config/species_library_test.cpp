// The shipped species library and the strictness of its loader.
#include "config/species_library.hpp"
#include "config/species_profile.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <set>

using namespace treelobes;
using treelobes::test::TempDir;

namespace {

std::filesystem::path shipped() { return test::source_dir() / "config" / "species.yaml"; }

// Loads a variant of the shipped file in which `from` (which must occur) is replaced by `to`,
// and returns the error it raises.
Error load_variant(const TempDir& dir, const std::string& from, const std::string& to) {
    std::string text = read_file(shipped());
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << "fixture text not found: " << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    const auto file = dir / "variant.yaml";
    test::write_text(file, text);
    try {
        load_species_profiles(file);
    } catch (const Error& e) {
        return e;
    }
    ADD_FAILURE() << "no error for variant " << from << " -> " << to;
    return Error(ExitCode::Ok, "");
}

}  // namespace

TEST(SpeciesLibrary, ShipsTwelveSpeciesWithTableOneParameters) {
    const auto entries = load_species_entries(shipped());
    ASSERT_EQ(entries.size(), 12u);
    // Livny et al. 2011, Table 1, verbatim.
    const std::map<std::string, std::array<double, 3>> table1 = {{"mahogany", {1.7, 1.3, 0.975}},
                                                                 {"bischofia_polycarpa", {1.8, 1.5, 0.986}},
                                                                 {"delonix", {1.7, 1.5, 0.982}},
                                                                 {"lagerstroemia", {1.6, 1.5, 0.976}},
                                                                 {"ailanthus_altissima", {1.5, 1.9, 0.980}},
                                                                 {"palm", {1.8, 1.3, 0.800}},
                                                                 {"terminalia", {1.5, 1.5, 0.970}},
                                                                 {"pine", {1.3, 1.2, 0.980}},
                                                                 {"willow", {1.5, 1.9, 0.980}},
                                                                 {"ficus_virens", {2.0, 1.6, 0.975}}};
    std::set<int> ids;
    for (const auto& e : entries) {
        ids.insert(e.id);
        const auto row = table1.find(e.name);
        if (row == table1.end()) continue;
        EXPECT_DOUBLE_EQ(e.reconstruction.beta, row->second[0]) << e.name;
        EXPECT_DOUBLE_EQ(e.reconstruction.gamma, row->second[1]) << e.name;
        EXPECT_DOUBLE_EQ(e.reconstruction.fs, row->second[2]) << e.name;
    }
    EXPECT_EQ(ids.size(), 12u);
    EXPECT_EQ(*ids.begin(), 1);
    EXPECT_EQ(*ids.rbegin(), 12);

    // The two species beyond Table 1 take the file's defaults and say so.
    const auto profiles = load_species_profiles(shipped());
    for (const char* extra : {"birch", "oak"}) {
        const auto& p = find_species_profile(profiles, extra);
        EXPECT_FALSE(p.reconstruction_from_table1) << extra;
        EXPECT_DOUBLE_EQ(p.entry.reconstruction.beta, 1.65);
    }
    EXPECT_TRUE(find_species_profile(profiles, "pine").reconstruction_from_table1);
}

TEST(SpeciesLibrary, LagerstroemiaPatchIsAppendixA) {
    const auto profiles = load_species_profiles(shipped());
    const PatchProfile& p = find_species_profile(profiles, "lagerstroemia").patch;
    EXPECT_EQ(p.chain_pts, 15);
    EXPECT_DOUBLE_EQ(p.phototropism, 0.2);
    EXPECT_DOUBLE_EQ(p.gravitropism, 0.3);
    EXPECT_DOUBLE_EQ(p.allometric, 1.2);
    EXPECT_DOUBLE_EQ(p.leaf_phototropism, 0.2);
    EXPECT_DOUBLE_EQ(p.leaf_gravitropism, 0.7);
    EXPECT_DOUBLE_EQ(p.face_up, 0.9);
    EXPECT_EQ(p.branch_distr, (std::array<int, 2>{1, 1}));
    EXPECT_EQ(p.num_twigs, 1);
    EXPECT_DOUBLE_EQ(p.branching_angle, 30);
    EXPECT_DOUBLE_EQ(p.spiral_angle, 180);
    EXPECT_DOUBLE_EQ(p.init_thickness, 1.0);
    EXPECT_EQ(p.leaf_distr, (std::array<int, 2>{1, 2}));
    EXPECT_EQ(p.num_leaves, 2);
    EXPECT_DOUBLE_EQ(p.leaf_angle, 40);
    EXPECT_DOUBLE_EQ(p.leaf_spiral_angle, 120);
    EXPECT_DOUBLE_EQ(p.orient_up, 0.8);
}

TEST(SpeciesLibrary, GrowthProfilesAreDistinct) {
    const auto profiles = load_species_profiles(shipped());
    const auto& willow = find_species_profile(profiles, "willow").growth;
    const auto& pine = find_species_profile(profiles, "pine").growth;
    const auto& palm = find_species_profile(profiles, "palm").growth;
    EXPECT_LT(willow.levels.back().tropism, -1.0);  // weeping branchlets
    EXPECT_GT(pine.levels[1].whorl, 1);             // whorls
    EXPECT_EQ(pine.levels[0].seg_splits, 0.0);      // apical dominance
    EXPECT_EQ(palm.levels.size(), 2u);              // unbranched trunk + fronds
    EXPECT_EQ(pine.leaves.shape, LeafShape::Needle);
    for (const auto& p : profiles) {
        EXPECT_GE(p.growth.levels.size(), 2u) << p.entry.name;
        EXPECT_LT(p.variation.height_m.min, p.variation.height_m.max) << p.entry.name;
    }
}

TEST(SpeciesLibrary, FindsSpeciesLeniently) {
    const auto entries = load_species_entries(shipped());
    EXPECT_EQ(find_species(entries, "Ficus Virens").name, "ficus_virens");
    EXPECT_EQ(find_species(entries, "ailanthus-altissima").id, 5);
    EXPECT_EQ(find_species(entries, "PINE").name, "pine");
    try {
        find_species(entries, "baobab");
        FAIL() << "baobab found";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::Usage);
        EXPECT_NE(std::string(e.what()).find("baobab"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("willow"), std::string::npos);  // lists the known names
    }
}

TEST(SpeciesLibrary, UnknownKeyNamesFileSpeciesAndKey) {
    TempDir dir;
    // A typo inserted into the pine's first-order branch level (growth.levels[1]); located by
    // structure rather than by its values, so tuning the profile does not break the fixture.
    std::string text = read_file(shipped());
    std::size_t at = text.find("- name: pine\n");
    ASSERT_NE(at, std::string::npos);
    at = text.find("levels:", at);
    ASSERT_NE(at, std::string::npos);
    for (int level = 0; level < 2 && at != std::string::npos; ++level) at = text.find("- {", at + 1);
    ASSERT_NE(at, std::string::npos);
    const std::string level1 = text.substr(at, text.find('\n', at) - at);
    const Error e = load_variant(dir, level1, "- {donw_angle: 3, " + level1.substr(3));
    EXPECT_EQ(e.code(), ExitCode::Usage);
    const std::string message = e.what();
    EXPECT_NE(message.find("variant.yaml"), std::string::npos) << message;
    EXPECT_NE(message.find("'pine'"), std::string::npos) << message;
    EXPECT_NE(message.find("growth.levels[1].donw_angle"), std::string::npos) << message;
    EXPECT_NE(message.find("unknown key"), std::string::npos) << message;
    EXPECT_NE(message.find("down_angle_v"), std::string::npos) << message;  // lists the allowed keys
}

TEST(SpeciesLibrary, OutOfRangeValuesAreRejected) {
    TempDir dir;
    Error e = load_variant(dir, "{beta: 1.3, gamma: 1.2, fs: 0.980}", "{beta: 1.3, gamma: 1.2, fs: 1.5}");
    EXPECT_EQ(e.code(), ExitCode::Usage);
    EXPECT_NE(std::string(e.what()).find("'pine'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("reconstruction.fs"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("outside"), std::string::npos) << e.what();

    e = load_variant(dir, "height_m: [12, 28]", "height_m: [28, 12]");
    EXPECT_NE(std::string(e.what()).find("variation.height_m"), std::string::npos) << e.what();

    e = load_variant(dir, "num_twigs: 4,", "num_twigs: 4.5,");
    EXPECT_NE(std::string(e.what()).find("patch.branching.num_twigs"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("integer"), std::string::npos) << e.what();

    e = load_variant(dir, "shape: needle", "shape: scale");
    EXPECT_NE(std::string(e.what()).find("growth.leaves.shape"), std::string::npos) << e.what();

    e = load_variant(dir, "segments: 10, curve_v: 6}", "segments: 0, curve_v: 6}");
    EXPECT_NE(std::string(e.what()).find("growth.levels[0].segments"), std::string::npos) << e.what();
}

TEST(SpeciesLibrary, StructuralErrorsAreRejected) {
    TempDir dir;
    Error e = load_variant(dir, "    id: 12\n", "    id: 3\n");
    EXPECT_EQ(e.code(), ExitCode::Usage);
    EXPECT_NE(std::string(e.what()).find("already used by 'delonix'"), std::string::npos) << e.what();

    e = load_variant(dir, "    display_name: Oak\n", "");
    EXPECT_NE(std::string(e.what()).find("'oak'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("missing required key"), std::string::npos) << e.what();

    e = load_variant(dir, "  - name: oak", "  - name: Oak Tree");
    EXPECT_NE(std::string(e.what()).find("lower-case"), std::string::npos) << e.what();

    e = load_variant(dir, "version: 1", "version: 2");
    EXPECT_NE(std::string(e.what()).find("version"), std::string::npos) << e.what();

    e = load_variant(dir, "    variation: {height_m: [10, 25], age_years: [10, 90]",
                     "    variation: {height_m: [10, 25], age_years: [10, 90], age_years: [1, 2]");
    EXPECT_EQ(e.code(), ExitCode::Usage) << e.what();
    EXPECT_NE(std::string(e.what()).find("duplicate key"), std::string::npos) << e.what();
}

TEST(SpeciesLibrary, MalformedYamlIsInvalidInputWithLine) {
    TempDir dir;
    const auto file = dir / "broken.yaml";
    test::write_text(file, "version: 1\nspecies:\n  - name: [unclosed\n");
    try {
        load_species_profiles(file);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ExitCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("broken.yaml"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("line"), std::string::npos) << e.what();
    }
    EXPECT_THROW(load_species_profiles(dir / "missing.yaml"), Error);
}

TEST(SpeciesLibrary, DefaultFileHonoursEnvironment) {
    ::unsetenv("TREELOBES_SPECIES");
    EXPECT_EQ(std::filesystem::weakly_canonical(default_species_file()), std::filesystem::weakly_canonical(shipped()));
    ::setenv("TREELOBES_SPECIES", "/tmp/other.yaml", 1);
    EXPECT_EQ(default_species_file(), std::filesystem::path("/tmp/other.yaml"));
    ::unsetenv("TREELOBES_SPECIES");
}

TEST(SpeciesLibrary, CrownShapeRatios) {
    EXPECT_DOUBLE_EQ(crown_shape_ratio(CrownShape::Conical, 1.0), 1.0);
    EXPECT_DOUBLE_EQ(crown_shape_ratio(CrownShape::Conical, 0.0), 0.2);
    EXPECT_NEAR(crown_shape_ratio(CrownShape::Spherical, 0.5), 1.0, 1e-12);
    EXPECT_DOUBLE_EQ(crown_shape_ratio(CrownShape::Flame, 0.7), 1.0);
    EXPECT_DOUBLE_EQ(crown_shape_ratio(CrownShape::InverseConical, 0.0), 1.0);
}
