// encode -> decode -> encode reproduces a .dbf6 byte for byte. The decoded skeleton PLY records
// the code's resolution, internode length and radius unit (encode/tree_code.hpp
// CodeParameters); `treelobes encode` takes them when no option overrides them, which is what
// the second encode here does. Checked on 1,000 random trees (short and zero-length edges,
// multi-way forks, several root stems, both coders, LODs) and on one grown tree of every
// species of the library, with the default internode length (the median edge).
#include "config/species_library.hpp"
#include "config/species_profile.hpp"
#include "core/skeleton_io.hpp"
#include "encode/tree_code.hpp"
#include "encode/tree_file.hpp"
#include "random_tree.hpp"
#include "support/test_support.hpp"
#include "synth/grow.hpp"

#include <gtest/gtest.h>

using namespace treelobes;
using namespace treelobes::encode;
using test::TempDir;

namespace {

std::vector<std::uint8_t> encoded_file(const TreeGraph& tree, const TreeFileOptions& options) {
    return write_tree_file_bytes(store_tree(tree, options));
}

// The .dbf6 bytes of encoding the decoded skeleton again, through a skeleton PLY file.
std::vector<std::uint8_t> reencoded_file(const std::vector<std::uint8_t>& file, TreeFileOptions options, const TempDir& dir) {
    const StoredTree stored = read_tree_file_bytes(file, -1, "first encoding");
    const auto ply = dir / "decoded.ply";
    write_skeleton_ply(decode_stored_tree(stored, 0, "first encoding"), ply, true,
                       {code_parameters_comment({stored.resolution, stored.internode_length, stored.radius_unit})});
    std::vector<std::string> comments;
    const TreeGraph decoded = read_skeleton_ply(ply, &comments);
    const std::optional<CodeParameters> recorded = find_code_parameters(comments, ply.string());
    EXPECT_TRUE(recorded.has_value());
    if (!recorded) return {};
    options.encode.resolution = recorded->resolution;
    options.encode.internode_length = recorded->internode_length;
    options.encode.radius_unit = recorded->radius_unit;
    return encoded_file(decoded, options);
}

struct Case {
    test::RandomTreeProfile profile;
    TreeFileOptions options;
};

// Shapes the round-trip tests avoid on purpose: edges down to a few percent of l (zero-length
// internodes after voxelization), coarse resolutions, multi-way forks and multi-stem roots.
Case make_case(std::uint32_t seed) {
    test::TreeRandom random(seed * 104729u + 3u);
    Case c;
    c.profile.max_nodes = 10 + random.below(250);
    c.profile.length_jitter = random.uniform() < 0.5 ? 0.3 : random.uniform(0.5, 0.97);
    c.profile.max_laterals = random.uniform() < 0.5 ? 1 : 2 + random.below(3);
    c.profile.wiggle_degrees = random.uniform() < 0.3 ? 0.0 : random.uniform(2.0, 30.0);
    c.profile.fork_probability = random.uniform(0.1, 0.5);
    c.profile.root_stems = random.uniform() < 0.8 ? 1 : 2 + random.below(3);
    c.profile.trunk_internodes = 3 + random.below(30);
    c.profile.tip_radius = random.uniform(0.0005, 0.004);
    const double resolutions[] = {1.5, 2.0, 3.0, 5.0, 10.0};
    c.options.encode.resolution = resolutions[random.below(5)];
    c.options.encode.internode_length = random.uniform() < 0.5 ? 0.0 : random.uniform(0.05, 0.2);
    c.options.encode.kind = random.uniform() < 0.5 ? CodeKind::F6 : CodeKind::DBF6;
    c.options.coder = random.uniform() < 0.5 ? Coder::Best : Coder::Interpolative;
    c.options.lods = 1 + random.below(3);
    return c;
}

}  // namespace

TEST(CodecIdempotence, ThousandRandomTrees) {
    TempDir dir;
    for (std::uint32_t seed = 1; seed <= 1000; ++seed) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        const Case c = make_case(seed);
        TreeGraph tree = test::random_tree(c.profile, seed);
        tree.origin = {612000.0 + seed, 5810000.0, 95.0};
        const auto first = encoded_file(tree, c.options);
        EXPECT_TRUE(reencoded_file(first, c.options, dir) == first);
        if (::testing::Test::HasFailure()) break;  // one failing seed is enough to read
    }
}

TEST(CodecIdempotence, GrownTreeOfEverySpecies) {
    TempDir dir;
    synth::GrowOptions grow;
    grow.leaves = false;
    for (const SpeciesProfile& species : load_species_profiles(default_species_file())) {
        SCOPED_TRACE(species.entry.name);
        const TreeGraph tree = synth::grow(species, 23, grow).skeleton;
        TreeFileOptions options;
        options.encode.resolution = 5.0;  // the default internode length: the median edge
        options.lods = 3;
        const auto first = encoded_file(tree, options);
        EXPECT_TRUE(reencoded_file(first, options, dir) == first);
    }
}
