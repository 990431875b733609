// `treelobes encode --out T.dbf6`, `encode --forest ... --out F.forest` and `treelobes decode`
// end to end: stats, LODs, random access to a forest tree, and one-line errors (exit 2) for
// truncated or corrupted files, exit 1 for bad options.
#include "core/atomic_file.hpp"
#include "core/skeleton_io.hpp"
#include "random_tree.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>

using treelobes::test::run_cli;
using treelobes::test::TempDir;

namespace {

using treelobes::test::quoted;

treelobes::TreeGraph cli_tree(std::uint32_t seed) {
    treelobes::test::RandomTreeProfile profile;
    profile.max_nodes = 300;
    profile.max_laterals = 2;
    profile.fork_probability = 0.35;
    return treelobes::test::random_tree(profile, seed);
}

std::string read_bytes(const std::filesystem::path& path) { return treelobes::read_file(path); }

void write_bytes(const std::filesystem::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

}  // namespace

TEST(FileCli, EncodeDecodeDbf6WithLodsAndStats) {
    TempDir dir;
    treelobes::TreeGraph tree = cli_tree(1);
    tree.origin = {500000.0, 4000000.0, 100.0};
    treelobes::write_skeleton_ply(tree, dir / "t.ply");
    for (const std::string coder : {"ic", "best"}) {
        const auto encoded = run_cli("--json encode " + quoted(dir / "t.ply") + " --resolution 5 --internode-length 0.1 --lods 3 --coder " +
                                     coder + " --stats --out " + quoted(dir / ("t_" + coder + ".dbf6")));
        ASSERT_EQ(encoded.exit_code, 0) << encoded.err;
        const auto json = nlohmann::json::parse(encoded.out);
        EXPECT_EQ(json["coder"], coder);
        ASSERT_EQ(json["lods"].size(), 3u);
        const std::size_t file_bytes = json["file_bytes"];
        EXPECT_EQ(file_bytes, std::filesystem::file_size(dir / ("t_" + coder + ".dbf6")));
        std::size_t streams = 0;
        for (const auto& lod : json["lods"]) streams += lod["symbol_bytes"].get<std::size_t>() + lod["radii_bytes"].get<std::size_t>();
        EXPECT_LT(streams, file_bytes);
        EXPECT_GT(json["lods"][0]["internodes"].get<int>(), json["lods"][2]["internodes"].get<int>());

        for (int lod : {0, 2}) {
            const auto out = dir / (treelobes::test::numbered("d", static_cast<std::size_t>(lod)) + ".ply");
            const auto decoded = run_cli("--json decode " + quoted(dir / ("t_" + coder + ".dbf6")) + " --lod " + std::to_string(lod) +
                                         " --out " + quoted(out));
            ASSERT_EQ(decoded.exit_code, 0) << decoded.err;
            const auto d = nlohmann::json::parse(decoded.out);
            EXPECT_EQ(d["internodes"], json["lods"][lod]["internodes"]);
            const treelobes::TreeGraph skeleton = treelobes::read_skeleton_ply(out);
            EXPECT_EQ(skeleton.size(), d["nodes"].get<std::size_t>());
            // World coordinates survive: the root is where it was.
            const Eigen::Vector3d root = skeleton.origin + skeleton.nodes[0].position.cast<double>();
            EXPECT_LT((root - (tree.origin + tree.nodes[0].position.cast<double>())).norm(), 1e-3);
        }
    }
    // Same input, same bytes.
    ASSERT_EQ(run_cli("encode " + quoted(dir / "t.ply") + " --resolution 5 --internode-length 0.1 --lods 3 --coder best --out " +
                      quoted(dir / "again.dbf6"))
                      .exit_code,
              0);
    EXPECT_EQ(read_bytes(dir / "again.dbf6"), read_bytes(dir / "t_best.dbf6"));
}

TEST(FileCli, ForestFromAListWithRandomAccess) {
    TempDir dir;
    std::string list = "# trees of the plot\n";
    for (int i = 0; i < 3; ++i) {
        treelobes::write_skeleton_ply(cli_tree(10 + i), dir / ("tree" + std::to_string(i) + ".ply"));
        list += "tree" + std::to_string(i) + ".ply " + std::to_string(10 * i) + " 5 0" + (i == 2 ? " 90" : "") + "\n";
    }
    write_bytes(dir / "trees.txt", list);
    const auto encoded = run_cli("--json encode --forest " + quoted(dir / "trees.txt") + " --resolution 5 --lods 2 --out " +
                                 quoted(dir / "plot.forest"));
    ASSERT_EQ(encoded.exit_code, 0) << encoded.err;
    EXPECT_EQ(nlohmann::json::parse(encoded.out)["trees"], 3);

    const auto one = run_cli("--json decode " + quoted(dir / "plot.forest") + " --tree 2 --lod 1 --out " + quoted(dir / "t2.ply"));
    ASSERT_EQ(one.exit_code, 0) << one.err;
    const treelobes::TreeGraph t2 = treelobes::read_skeleton_ply(dir / "t2.ply");
    EXPECT_NEAR(t2.origin.x() + t2.nodes[0].position.x(), 20.0, 1e-3);
    EXPECT_NEAR(t2.origin.y() + t2.nodes[0].position.y(), 5.0, 1e-3);

    const auto all = run_cli("decode " + quoted(dir / "plot.forest") + " --out " + quoted(dir / "decoded"));
    ASSERT_EQ(all.exit_code, 0) << all.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "decoded" / "00000_tree0.ply"));
    EXPECT_TRUE(std::filesystem::exists(dir / "decoded" / "00002_tree2.ply"));

    // A directory of skeletons works too (trees stand where their roots are).
    std::filesystem::create_directory(dir / "plot");
    std::filesystem::copy_file(dir / "tree0.ply", dir / "plot" / "a.ply");
    std::filesystem::copy_file(dir / "tree1.ply", dir / "plot" / "b.ply");
    const auto from_dir = run_cli("--json encode --forest " + quoted(dir / "plot") + " --resolution 3 --out " + quoted(dir / "d.forest"));
    ASSERT_EQ(from_dir.exit_code, 0) << from_dir.err;
    EXPECT_EQ(nlohmann::json::parse(from_dir.out)["trees"], 2);
    EXPECT_EQ(run_cli("decode " + quoted(dir / "plot.forest") + " --tree 3 --out " + quoted(dir / "x.ply")).exit_code, 1);
}

TEST(FileCli, DamagedFilesExitWithTwoAndOneLine) {
    TempDir dir;
    treelobes::write_skeleton_ply(cli_tree(2), dir / "t.ply");
    ASSERT_EQ(run_cli("encode " + quoted(dir / "t.ply") + " --resolution 5 --out " + quoted(dir / "t.dbf6")).exit_code, 0);
    write_bytes(dir / "list.txt", "t.ply\n");
    ASSERT_EQ(run_cli("encode --forest " + quoted(dir / "list.txt") + " --resolution 5 --out " + quoted(dir / "f.forest")).exit_code, 0);
    const std::string dbf6 = read_bytes(dir / "t.dbf6"), forest = read_bytes(dir / "f.forest");
    std::string flipped = dbf6;
    flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 0x20);
    std::string forest_flipped = forest;
    forest_flipped[forest.size() - 10] = static_cast<char>(forest_flipped[forest.size() - 10] ^ 0x01);
    const struct {
        std::string name, bytes, message;
    } cases[] = {
            {"cut.dbf6", dbf6.substr(0, dbf6.size() - 7), "checksum mismatch"},
            {"flip.dbf6", flipped, "checksum mismatch"},
            {"short.dbf6", dbf6.substr(0, 3), "not a .dbf6 file"},
            {"cut.forest", forest.substr(0, forest.size() - 5), "truncated"},
            {"flip.forest", forest_flipped, "checksum mismatch in tree 0"},
            {"empty.forest", "DBFF", "truncated"},
    };
    for (const auto& c : cases) {
        write_bytes(dir / c.name, c.bytes);
        const auto result = run_cli("decode " + quoted(dir / c.name) + " --out " + quoted(dir / "x.ply"));
        EXPECT_EQ(result.exit_code, 2) << c.name << "\n" << result.err;
        EXPECT_NE(result.err.find(c.message), std::string::npos) << c.name << "\n" << result.err;
        EXPECT_NE(result.err.find(c.name), std::string::npos) << result.err;
        EXPECT_EQ(std::count(result.err.begin(), result.err.end(), '\n'), 1) << result.err;
        EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
    }
    write_bytes(dir / "bad_list.txt", "t.ply 1 2\n");
    const auto bad_list = run_cli("encode --forest " + quoted(dir / "bad_list.txt") + " --resolution 5 --out " + quoted(dir / "g.forest"));
    EXPECT_EQ(bad_list.exit_code, 2);
    EXPECT_NE(bad_list.err.find("line 1"), std::string::npos) << bad_list.err;
}

TEST(FileCli, BadOptionsExitWithOne) {
    TempDir dir;
    treelobes::write_skeleton_ply(cli_tree(3), dir / "t.ply");
    const std::string file = quoted(dir / "t.ply");
    EXPECT_EQ(run_cli("encode " + file + " --resolution 5 --out x.dbf6 --coder zip").exit_code, 1);
    EXPECT_EQ(run_cli("encode " + file + " --resolution 5 --out x.dbf6 --lods 0").exit_code, 1);
    EXPECT_EQ(run_cli("encode " + file + " --resolution 5 --lods 3").exit_code, 1);                // --lods needs --out
    EXPECT_EQ(run_cli("encode --resolution 5 --out x.dbf6").exit_code, 1);                         // no input
    EXPECT_EQ(run_cli("encode --forest " + quoted(dir.path()) + " --resolution 5").exit_code, 1);  // forest without --out
    ASSERT_EQ(run_cli("encode " + file + " --resolution 5 --lods 2 --out " + quoted(dir / "t.dbf6")).exit_code, 0);
    EXPECT_EQ(run_cli("decode " + quoted(dir / "t.dbf6") + " --lod 2 --out " + quoted(dir / "x.ply")).exit_code, 1);
    EXPECT_EQ(run_cli("decode " + quoted(dir / "t.dbf6") + " --tree 0 --out " + quoted(dir / "x.ply")).exit_code, 1);
    EXPECT_EQ(run_cli("decode " + quoted(dir / "t.dbf6")).exit_code, 1);  // --out is required
}

// encode -> decode -> encode with the same options gives the same file: the decoded PLY records
// r, l and the radius unit, and encode takes them when no option overrides them (so even
// without --resolution).
TEST(FileCli, EncodeDecodeEncodeReproducesTheFile) {
    const std::filesystem::path data = treelobes::test::source_dir() / "data/synthetic";
    for (const std::string skeleton : {"birch_3_skeleton.ply", "lagerstroemia_2_skeleton.ply", "palm_1_skeleton.ply"}) {
        SCOPED_TRACE(skeleton);
        TempDir dir;
        const std::string options = " --resolution 4 --lods 2";
        ASSERT_EQ(run_cli("encode " + quoted(data / skeleton) + options + " --out " + quoted(dir / "a.dbf6")).exit_code, 0);
        ASSERT_EQ(run_cli("decode " + quoted(dir / "a.dbf6") + " --out " + quoted(dir / "a.ply")).exit_code, 0);
        ASSERT_EQ(run_cli("encode " + quoted(dir / "a.ply") + options + " --out " + quoted(dir / "b.dbf6")).exit_code, 0);
        EXPECT_TRUE(read_bytes(dir / "a.dbf6") == read_bytes(dir / "b.dbf6"));
        ASSERT_EQ(run_cli("encode " + quoted(dir / "a.ply") + " --lods 2 --out " + quoted(dir / "c.dbf6")).exit_code, 0);
        EXPECT_TRUE(read_bytes(dir / "a.dbf6") == read_bytes(dir / "c.dbf6"));
    }
    // A skeleton that records nothing still needs --resolution (one line, exit 1).
    TempDir dir;
    const auto r = run_cli("encode " + quoted(data / "palm_1_skeleton.ply") + " --out " + quoted(dir / "x.dbf6"));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("--resolution is required"), std::string::npos) << r.err;
}
