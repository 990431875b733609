// The bad-input corpus (tests/data/bad, written by make_bad_inputs.py): one small file per
// failure class, and what the CLI must answer to each: exit code 2, one line on stderr naming
// the file (or the option) and the problem, and no output file left behind. Valid but odd input
// (a house instead of a tree) finishes with a documented quality flag instead. Batch commands
// (reconstruct) record the failure in failures.jsonl, their one documented file on failure.
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

using namespace treelobes;
using test::quoted;
using test::TempDir;

namespace {

struct BadInput {
    const char* file;     // in tests/data/bad
    const char* command;  // {in}: the file, {out}: an output path in an empty folder
    const char* problem;  // what the one-line message must say
};

std::filesystem::path bad_file(const std::string& name) { return test::source_dir() / "tests/data/bad" / name; }

std::string replaced(std::string text, const std::string& key, const std::string& value) {
    for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + value.size()))
        text.replace(at, key.size(), value);
    return text;
}

std::string read_text(const std::filesystem::path& path) {
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), {}};
}

std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::string line;
    std::istringstream stream(text);
    while (std::getline(stream, line))
        if (!line.empty()) lines.push_back(line);
    return lines;
}

// True when the folder holds nothing but (in a batch output folder) failures.jsonl.
bool only_failure_records(const std::filesystem::path& folder) {
    for (const auto& entry : std::filesystem::recursive_directory_iterator(folder))
        if (entry.is_regular_file() && entry.path().filename() != "failures.jsonl") return false;
    return true;
}

const BadInput kCorpus[] = {
        {"truncated.las", "render {in} --out {out}.png", "truncated"},
        {"wrong_magic.las", "render {in} --out {out}.png", "LASF"},
        {"count_exceeds_file.las", "render {in} --out {out}.png", "declares 1000000 points"},
        {"absurd_scale.las", "render {in} --out {out}.png", "x scale 1e+300 and offset 0 give coordinates beyond 1e30"},
        {"empty_tile.las", "reconstruct {in} --out {out}", "too few points for a tree (0)"},
        {"count_overflow.ply", "render {in} --out {out}.png", "element <name> <count>"},
        {"negative_count.ply", "render {in} --out {out}.png", "element <name> <count>"},
        {"nan.xyz", "render {in} --out {out}.png", "all 50 points have NaN/inf coordinates"},
        {"inf.xyz", "render {in} --out {out}.png", "all 50 points have NaN/inf coordinates"},
        {"two_points.xyz", "reconstruct {in} --out {out}", "too few points"},
        {"identical_points.xyz", "reconstruct {in} --out {out}", "too few points left after removing duplicates"},
        {"house.xyz", "reconstruct {in} --out {out} --reject-non-trees", "not a tree"},
        {"skeleton_cycle.ply", "encode {in} --resolution 5 --out {out}.dbf6", "skeleton edges contain a cycle"},
        {"skeleton_two_roots.ply", "encode {in} --resolution 5 --out {out}.dbf6", "needs 4 edges, found 3"},
        {"truncated.dbf6", "decode {in} --out {out}.ply", "truncated"},
        {"wrong_magic.dbf6", "decode {in} --out {out}.ply", "magic"},
        {"absurd_count.forest", "decode {in} --out {out}", "tree count"},
        {"absurd_size.tlobe", "synthesize {in} --out {out}.ply", "payload size"},
};

class BadInputCorpus : public testing::TestWithParam<BadInput> {};

}  // namespace

TEST_P(BadInputCorpus, ExitsWithCodeTwoAndOneLineNamingTheProblemAndLeavesNoOutput) {
    const BadInput& c = GetParam();
    TempDir dir;
    const std::string command = replaced(replaced(c.command, "{in}", quoted(bad_file(c.file))), "{out}", quoted(dir / "out"));
    const auto r = test::run_cli(command + " --log-level error");
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.err;
    const auto lines = lines_of(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.err;
    const auto file_named_at = lines[0].find(c.file);
    ASSERT_NE(file_named_at, std::string::npos) << "the message names the file: " << lines[0];
    // After the file's name: "truncated.las" must not pass for a message that says "truncated".
    const std::string message = lines[0].substr(file_named_at + std::string_view(c.file).size());
    EXPECT_NE(message.find(c.problem), std::string::npos) << "the message names the problem: " << lines[0];
    EXPECT_TRUE(only_failure_records(dir.path())) << "output left behind by " << command;
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInputCorpus, testing::ValuesIn(kCorpus), [](const auto& param) {
    std::string name = param.param.file;
    for (char& ch : name)
        if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
    return name;
});

// A code whose fork never gets its lateral comes as option values, not as a file.
TEST(BadInputCorpus, UnbalancedForksInAChainCode) {
    const auto lines = lines_of(read_text(bad_file("unbalanced_forks.code")));
    ASSERT_EQ(lines.size(), 2u);
    TempDir dir;
    const auto r = test::run_cli("decode-code --code " + lines[0] + " --radii " + lines[1] +
                                 " --resolution 5 --internode-length 0.1 --out " + quoted(dir / "out.ply") + " --log-level error");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const auto err = lines_of(r.err);
    ASSERT_EQ(err.size(), 1u) << r.err;
    EXPECT_NE(err[0].find("--code"), std::string::npos) << err[0];
    EXPECT_NE(err[0].find("fork"), std::string::npos) << err[0];
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

// Valid but odd: a house reconstructs (exit 0) and the summary flags it as not a tree.
TEST(BadInputCorpus, HouseIsFlaggedNotATree) {
    TempDir dir;
    const auto r =
            test::run_cli("reconstruct " + quoted(bad_file("house.xyz")) + " --out " + quoted(dir / "out") + " --json --log-level error");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto summary = nlohmann::json::parse(r.out);
    const auto& quality = summary.at("trees").at(0).at("quality");
    EXPECT_TRUE(quality.at("not_a_tree").get<bool>()) << r.out;
    EXPECT_EQ(quality.at("flags").at(0), "not_a_tree") << r.out;
}
