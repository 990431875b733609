// Every flag of every subcommand reaches its summary: each row runs one subcommand on a small
// input (a few flags set away from their defaults), reads its summary (the summary file, or the
// --json output of commands without one) and checks that each flag the CLI declares for that
// subcommand (walked in the CLI11 app itself, not listed here) appears in the summary's options,
// and that the flags set show the values given. A flag added without going through the option
// table, or a summary that builds its options by hand, fails here.
#include "apps/command.hpp"
#include "apps/option_table.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using namespace treelobes;
using test::quoted;
using test::TempDir;
namespace fs = std::filesystem;

namespace {

struct Row {
    const char* command;    // the subcommand's path, e.g. "classify train"
    const char* arguments;  // {in}: shared inputs, {data}: data/synthetic, {src}: the source tree, {out}: this run's folder
    const char* summary;    // the summary file under {out}, or "" for the --json output on stdout
    const char* options;    // JSON pointer to the options object in the summary
    const char* expected;   // options the arguments set, with the values they must show
};

const Row kRows[] = {
        {"info", "--json info {data}/palm_1.las --bounds -50,-50,50,50", "", "/options", R"({"bounds": "-50,-50,50,50"})"},
        {"convert", "--json convert {data}/palm_1.las --out {out}/palm_1.ply --bounds -50,-50,50,50", "", "/options",
         R"({"bounds": "-50,-50,50,50"})"},
        {"multires", "--json multires {src}/lsystem/examples/stochastic_bush.lsys --out {out} --all --texture-size 16", "", "/options",
         R"({"all": true, "texture_size": 16, "lod": []})"},
        {"reconstruct", "reconstruct {data}/palm_1.las --out {out} --geodesic-smoothing 2 --fit-axes false --mesh-sides 6 --species palm",
         "palm_1_summary.json", "/options",
         R"({"geodesic_smoothing": 2, "fit_axes": false, "mesh_sides": 6, "species": "palm", "overwrite": false})"},
        {"eval skeleton",
         "--json eval skeleton --skeleton {data}/birch_3_skeleton.ply --reference {data}/palm_1_skeleton.ply --match-distance 0.2", "",
         "/options", R"({"match_distance": 0.2})"},
        {"encode", "--json encode {data}/birch_3_skeleton.ply --resolution 5 --lods 3 --out {out}/birch.dbf6", "", "/options",
         R"({"resolution": 5, "lods": 3})"},
        {"decode", "--json decode {in}/birch.dbf6 --lod 1 --out {out}/birch.ply", "", "/options", R"({"lod": 1})"},
        {"lod", "--json lod --code 00080006000700087 --radii 9,8,4,6,3 --levels 3", "", "/options", R"({"levels": 3})"},
        {"decode-code",
         "--json decode-code --code 00080006000700087 --radii 9,8,4,6,3 --resolution 5 --internode-length 0.1 --out {out}/code.ply", "",
         "/options", R"({"internode_length": 0.1, "f6": false})"},
        {"render", "--json render {data}/palm_1_skeleton.ply --out {out}/preview.png --size 100", "", "/options", R"({"size": 100})"},
        {"synth tree", "--json synth tree --species palm --height 4 --seed 3 --max-leaves 2000 --out {out}", "", "/options",
         R"({"height": 4, "seed": 3, "max_leaves": 2000})"},
        {"synth dataset", "synth dataset --species palm --per-species 1 --seed 2 --max-leaves 2000 --angular-step 1 --out {out}",
         "summary.json", "/options", R"({"per_species": 1, "species": ["palm"], "angular_step": 1})"},
        {"synth tile", "--json synth tile --trees 2 --size 12 --seed 4 --no-leaves --out {out}", "", "/options",
         R"({"trees": 2, "size": 12, "no_leaves": true})"},
        {"classify features",
         "--json classify features {in}/clouds/birch_3_1.las --relative-to {in}/clouds --no-skeleton --out {out}/features.csv", "",
         "/options", R"({"no_skeleton": true})"},
        {"classify train",
         "--json classify train {in}/features.csv --labels {in}/labels.csv --out {out}/model.json --folds 0 --max-rounds 20 "
         "--no-scan-routing",
         "", "/options", R"({"folds": 0, "max_rounds": 20, "no_scan_routing": true, "no_calibration": false})"},
        {"classify predict", "--json classify predict {in}/model.json {in}/features.csv --radius 3 --out {out}/predictions.csv", "",
         "/options", R"({"radius": 3, "vote": false})"},
        {"classify evaluate",
         "classify evaluate {in}/clouds --features {in}/features.csv --splits 4 --max-rounds 20 --no-xgboost --out {out}", "summary.json",
         "/options", R"({"splits": 4, "max_rounds": 20, "no_xgboost": true})"},
        {"lobes", "lobes {data}/palm_1.las --out {out} --face-budget 500 --beta 1.6", "palm_1_lobes.json", "/options",
         R"({"face_budget": 500, "beta": 1.6})"},
        {"synthesize", "synthesize {in}/lobes/palm_1.tlobe --out {out}/palm.ply --max-triangles 20000", "palm.json", "/options",
         R"({"max_triangles": 20000})"},
        {"export", "--json export {data}/birch_3_skeleton.ply --format glb --out {out}/birch.glb --sides 5 --no-leaves", "", "/options",
         R"({"format": "glb", "sides": 5, "no_leaves": true})"},
        {"rebuild",
         "rebuild {in}/palm/palm_3_mesh.obj --out {out} --species palm --samples 20000 --compare-samples 2000 --max-triangles 20000 "
         "--image-height 160",
         "report.json", "/options", R"({"samples": 20000, "image_height": 160, "species": "palm"})"},
        {"compare", "--json compare {in}/palm/palm_3_mesh.obj {in}/palm/palm_3_mesh.obj --compare-samples 2000 --silhouette-px 64", "",
         "/options", R"({"compare_samples": 2000, "silhouette_px": 64, "crown_closing_px": 8})"},
        {"tile", "tile {data}/tile/tile.las --out {out} --map-size 300 --min-tree-points 30", "summary.json", "/options",
         R"({"map_size": 300, "mode": "auto", "min_tree_points": 30})"},
        {"batch", "--json batch {in}/tiles --out {out} --max-memory 8G --map-size 300", "", "/options", R"({"max_memory": "8G"})"},
        {"merge", "--json merge {in}/tile --out {out}", "", "/merge_options", "{}"},
        {"retile", "--json retile {data}/palm_1.las --size 5 --prefix part --out {out}", "", "/options",
         R"({"size": 5, "prefix": "part"})"},
};

std::string replaced(std::string text, const std::string& key, const std::string& value) {
    for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + value.size()))
        text.replace(at, key.size(), value);
    return text;
}

// The inputs a row reads from {in} (other commands' outputs), made on first use: each row runs in
// a process of its own, so it makes only what it reads.
class Inputs {
public:
    static fs::path for_arguments(const std::string& arguments) {
        static Inputs inputs;
        const auto wants = [&](const std::string& name) { return arguments.find("{in}/" + name) != std::string::npos; };
        if (wants("clouds") || wants("features.csv") || wants("labels.csv") || wants("model.json")) inputs.make_clouds();
        if (wants("features.csv") || wants("model.json"))
            inputs.run("classify features " + quoted(inputs.in() / "clouds") + "/*.las --relative-to " + quoted(inputs.in() / "clouds") +
                       " --no-skeleton --out " + quoted(inputs.in() / "features.csv"));
        if (wants("model.json"))
            inputs.run("classify train " + quoted(inputs.in() / "features.csv") + " --labels " + quoted(inputs.in() / "labels.csv") +
                       " --out " + quoted(inputs.in() / "model.json") + " --folds 0 --max-rounds 20 --no-scan-routing");
        if (wants("lobes")) inputs.run("lobes " + quoted(inputs.data() / "palm_1.las") + " --out " + quoted(inputs.in() / "lobes"));
        if (wants("birch.dbf6"))
            inputs.run("encode " + quoted(inputs.data() / "birch_3_skeleton.ply") + " --resolution 5 --lods 3 --out " +
                       quoted(inputs.in() / "birch.dbf6"));
        if (wants("palm/"))
            inputs.run("synth tree --species palm --seed 3 --height 6 --max-leaves 4000 --angular-step 0.5 --mesh-format obj --out " +
                       quoted(inputs.in() / "palm"));
        if (wants("tiles")) {
            fs::create_directories(inputs.in() / "tiles");
            fs::copy_file(inputs.data() / "tile/tile.las", inputs.in() / "tiles" / "tile.las");
        }
        if (wants("tile "))
            inputs.run("tile " + quoted(inputs.data() / "tile/tile.las") + " --min-tree-points 30 --out " + quoted(inputs.in() / "tile"));
        return inputs.in();
    }

private:
    const fs::path& in() const { return dir_.path(); }
    fs::path data() const { return test::source_dir() / "data/synthetic"; }
    // Two copies of two trees with labels.csv (here and beside the clouds).
    void make_clouds() {
        fs::create_directories(in() / "clouds");
        std::ofstream labels(in() / "labels.csv");
        labels << "file,species\n";
        for (const char* tree : {"birch_3", "palm_1"})
            for (int copy : {1, 2}) {
                const std::string id = std::string(tree) + "_" + std::to_string(copy);
                fs::copy_file(data() / (std::string(tree) + ".las"), in() / "clouds" / (id + ".las"));
                labels << id << ".las," << std::string(tree).substr(0, std::string(tree).find('_')) << "\n";
            }
        labels.close();
        fs::copy_file(in() / "labels.csv", in() / "clouds" / "labels.csv");
    }
    void run(const std::string& arguments) {
        const auto r = test::run_cli(arguments + " --log-level error");
        if (r.exit_code != 0) ADD_FAILURE() << "preparing the inputs: treelobes " << arguments << "\n" << r.err;
    }
    TempDir dir_;
};

// The whole CLI as `treelobes` builds it.
struct Cli {
    CLI::App app;
    cli::GlobalOptions global;
    cli::Job job;
    Cli() { cli::add_commands(app, global, job); }
};

CLI::App* subcommand(CLI::App& app, const std::string& path) {
    CLI::App* command = &app;
    std::istringstream names(path);
    for (std::string name; names >> name;) command = command->get_subcommand(name);
    return command;
}

// The summary keys of the flags `command` declares: every option with a long name but --help.
std::set<std::string> declared_keys(const CLI::App& command) {
    std::set<std::string> keys;
    for (const CLI::Option* option : command.get_options())
        if (!option->get_lnames().empty() && option != command.get_help_ptr() && option != command.get_help_all_ptr())
            keys.insert(cli::summary_key(*option));
    return keys;
}

void collect_leaves(const CLI::App& command, const std::string& path, std::set<std::string>& leaves) {
    const auto subcommands = command.get_subcommands({});
    if (subcommands.empty()) leaves.insert(path);
    for (const CLI::App* sub : subcommands) collect_leaves(*sub, path.empty() ? sub->get_name() : path + " " + sub->get_name(), leaves);
}

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

class OptionSummary : public testing::TestWithParam<Row> {};

// gtest names a failing row by its command line.
void PrintTo(const Row& row, std::ostream* out) { *out << row.arguments; }

}  // namespace

TEST(OptionSummaryTable, CoversEverySubcommand) {
    Cli cli;
    std::set<std::string> leaves, rows;
    collect_leaves(cli.app, "", leaves);
    for (const Row& row : kRows) rows.insert(row.command);
    EXPECT_EQ(leaves, rows) << "a subcommand without a row in kRows (or a row for none)";
}

TEST(OptionSummaryTable, SummaryKeyIsTheLongNameWithUnderscores) {
    CLI::App app;
    std::string text;
    bool flag = true;
    EXPECT_EQ(cli::summary_key(*app.add_option("--mesh-sides", text)), "mesh_sides");
    EXPECT_EQ(cli::summary_key(*app.add_option("-o,--out", text)), "out");
    EXPECT_EQ(cli::summary_key(*app.add_flag("--no-calibration{false}", flag)), "no_calibration");
}

TEST(OptionTable, ReportsResolvedValuesAndSwitchesAsGiven) {
    CLI::App app;
    cli::OptionTable table(&app);
    float ratio = 0.3f;
    std::optional<double> beta;
    bool calibrate = true, list = false;
    std::vector<int> lods;
    table.add("--ratio", ratio, "a float");
    table.add("--beta", beta, "unset: null");
    table.add("--lods", lods, "a list");
    table.add_flag("--no-calibration{false}", calibrate, "clears calibrate");
    table.add_flag("--list", list, "a switch");
    app.parse(std::vector<std::string>{"--no-calibration", "3", "--lods", "1", "--lods"});  // CLI11 parses last first
    const nlohmann::json options = table.json();
    EXPECT_EQ(options.dump(), R"({"beta":null,"list":false,"lods":[1,3],"no_calibration":true,"ratio":0.3})");
    table.report_as("--beta", [] { return 1.5; });
    EXPECT_EQ(table.json()["beta"], 1.5);
    EXPECT_THROW(table.report_as("--gamma", [] { return 1; }), std::logic_error);
}

TEST_P(OptionSummary, EveryDeclaredFlagAppearsWithItsResolvedValue) {
    const Row& row = GetParam();
    TempDir dir;
    const fs::path out = dir / "out";
    std::string arguments = replaced(row.arguments, "{in}", Inputs::for_arguments(row.arguments).string());
    arguments = replaced(arguments, "{data}", (test::source_dir() / "data/synthetic").string());
    arguments = replaced(arguments, "{src}", test::source_dir().string());
    arguments = replaced(arguments, "{out}", out.string());
    if (arguments.find(out.string() + "/") != std::string::npos) fs::create_directories(out);
    const auto r = test::run_cli("--log-level error " + arguments);
    ASSERT_EQ(r.exit_code, 0) << "treelobes " << arguments << "\n" << r.err;
    const std::string text = std::string(row.summary).empty() ? r.out : read_text(out / row.summary);
    const nlohmann::json summary = nlohmann::json::parse(text);
    const nlohmann::json::json_pointer pointer(row.options);
    ASSERT_TRUE(summary.contains(pointer)) << row.options << " missing in\n" << text;
    const nlohmann::json& options = summary.at(pointer);

    Cli cli;
    const CLI::App* command = subcommand(cli.app, row.command);
    ASSERT_NE(command, nullptr);
    const std::set<std::string> declared = declared_keys(*command);
    EXPECT_FALSE(declared.empty());
    for (const std::string& key : declared)
        EXPECT_TRUE(options.contains(key)) << "the summary's options lack \"" << key << "\", a declared flag";
    const nlohmann::json expected = nlohmann::json::parse(row.expected);
    for (const auto& item : expected.items()) {
        EXPECT_TRUE(declared.count(item.key())) << item.key() << " is no flag of " << row.command;
        EXPECT_EQ(options.value(item.key(), nlohmann::json()), item.value()) << item.key();
    }
}

INSTANTIATE_TEST_SUITE_P(Subcommands, OptionSummary, testing::ValuesIn(kRows), [](const auto& param) {
    std::string name = param.param.command;
    for (char& c : name)
        if (c == ' ' || c == '-') c = '_';
    return name;
});
