// Every subcommand gives byte-identical outputs with --threads 1 and --threads 2 (and another heap layout): each row of
// the table runs twice into two folders, and every file (and the --json summary on stdout) is
// compared. JSON summaries are compared without their timing and memory fields (the only
// values allowed to differ, DESIGN.md "summary.json") and without the thread count; the one
// other file with timings, the report.md of `classify evaluate` (its run time and the train and
// CPU seconds per split), is compared with exactly those masked, and so are the run times of the
// human summaries on stdout.
#include "support/test_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

using namespace treelobes;
using test::quoted;
using test::TempDir;
namespace fs = std::filesystem;

namespace {

struct Command {
    const char* name;
    const char* arguments;  // {in}: the shared inputs, {data}: data/synthetic, {out}: this run's folder
};

// Inputs made once for the commands that read other commands' outputs.
class Inputs {
public:
    static const fs::path& folder() {
        static Inputs inputs;
        return inputs.dir_.path();
    }

private:
    Inputs() {
        const fs::path data = test::source_dir() / "data/synthetic";
        const fs::path in = dir_.path();
        fs::create_directories(in / "clouds");
        std::ofstream labels(in / "labels.csv");
        labels << "file,species\n";
        for (const char* tree : {"birch_3", "lagerstroemia_2", "palm_1"})
            for (int copy : {1, 2}) {
                const std::string id = std::string(tree) + "_" + std::to_string(copy);
                fs::copy_file(data / (std::string(tree) + ".las"), in / "clouds" / (id + ".las"));
                labels << id << ".las," << std::string(tree).substr(0, std::string(tree).find('_')) << "\n";
            }
        labels.close();
        fs::copy_file(in / "labels.csv", in / "clouds" / "labels.csv");
        run("classify features " + quoted(in / "clouds") + "/*.las --relative-to " + quoted(in / "clouds") + " --out " +
            quoted(in / "features.csv"));
        run("classify train " + quoted(in / "features.csv") + " --labels " + quoted(in / "labels.csv") + " --out " +
            quoted(in / "model.json") + " --folds 0 --max-rounds 20 --no-scan-routing");
        run("lobes " + quoted(data / "palm_1.las") + " --out " + quoted(in / "lobes"));
        run("encode " + quoted(data / "birch_3_skeleton.ply") + " --resolution 5 --lods 3 --out " + quoted(in / "birch.dbf6"));
        fs::create_directories(in / "skeletons");
        for (const char* tree : {"birch_3", "lagerstroemia_2", "palm_1"})
            fs::copy_file(data / (std::string(tree) + "_skeleton.ply"), in / "skeletons" / (std::string(tree) + ".ply"));
        run("encode --forest " + quoted(in / "skeletons") + " --resolution 5 --out " + quoted(in / "tile.forest"));
    }
    static void run(const std::string& arguments) {
        const auto r = test::run_cli(arguments + " --log-level error");
        if (r.exit_code != 0) ADD_FAILURE() << "preparing the inputs: treelobes " << arguments << "\n" << r.err;
    }
    TempDir dir_;
};

const Command kCommands[] = {
        {"info", "info {data}/palm_1.las {data}/palm_1_skeleton.ply {data}/palm_1_mesh.ply --json"},
        {"synth_tree", "synth tree --species palm --height 4 --seed 3 --out {out}"},
        {"synth_tile", "synth tile --trees 2 --size 12 --seed 4 --no-leaves --out {out}"},
        {"reconstruct", "reconstruct {data}/palm_1.las {data}/birch_3.las --out {out} --json"},
        {"eval_skeleton", "eval skeleton --skeleton {data}/birch_3_skeleton.ply --reference {data}/palm_1_skeleton.ply --json"},
        {"lobes", "lobes {data}/palm_1.las --out {out} --json"},
        {"synthesize", "synthesize {in}/lobes/palm_1.tlobe --out {out}/palm.ply --json"},
        {"classify_features",
         "classify features {in}/clouds/birch_3_1.las {in}/clouds/palm_1_1.las --relative-to {in}/clouds --out {out}/features.csv"},
        {"classify_train",
         "classify train {in}/features.csv --labels {in}/labels.csv --out {out}/model.json --folds 2 --max-rounds 30 --no-scan-routing"},
        {"classify_predict", "classify predict {in}/model.json {in}/features.csv --out {out}/predictions.csv"},
        {"classify_evaluate", "classify evaluate {in}/clouds --features {in}/features.csv --splits 4 --max-rounds 20 --out {out}"},
        {"encode", "encode {data}/birch_3_skeleton.ply --resolution 5 --lods 3 --out {out}/birch.dbf6 --json"},
        {"encode_forest", "encode --forest {in}/skeletons --resolution 5 --lods 2 --out {out}/tile.forest --json"},
        {"decode", "decode {in}/birch.dbf6 --lod 1 --out {out}/birch.ply --json"},
        {"decode_forest", "decode {in}/tile.forest --out {out}/trees --json"},
        {"lod", "lod --code 00080006000700087 --radii 9,8,4,6,3 --levels 3 --json"},
        {"decode_code",
         "decode-code --code 00080006000700087 --radii 9,8,4,6,3 --resolution 5 --internode-length 0.1 --out {out}/code.ply --json"},
        {"multires", "multires {src}/lsystem/examples/stochastic_bush.lsys --out {out} --all --json"},
        {"render", "render {data}/palm_1.las {data}/palm_1_skeleton.ply --out {out}/preview.png"},
        {"convert", "convert {data}/palm_1.las --out {out}/palm_1.ply --json"},
        {"tile", "tile {data}/tile/tile.las --out {out}/tile --json --min-tree-points 30"},  // every segment modelled: exit 0
        {"rebuild",
         "rebuild {data}/palm_1_mesh.ply --out {out} --species palm --samples 20000 --compare-samples 2000 --max-triangles 20000 "
         "--image-height 160 --json"},
        {"compare", "compare {data}/palm_1_mesh.ply {data}/palm_1_mesh.ply --compare-samples 2000 --png {out}/crowns.png --json"},
        {"export_glb", "export {data}/birch_3_skeleton.ply --format glb --out {out}/birch.glb --json"},
        {"export_qsm", "export {data}/birch_3_skeleton.ply --format qsm-csv --out {out}/birch.csv --json"},
};

std::string replaced(std::string text, const std::string& key, const std::string& value) {
    for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + value.size()))
        text.replace(at, key.size(), value);
    return text;
}

// Timings, memory and the thread count are the values a summary may vary in.
bool varies_by_run(const std::string& key) {
    return key.find("seconds") != std::string::npos || key.find("memory") != std::string::npos || key == "threads";
}

nlohmann::json without_run_values(nlohmann::json j) {
    if (j.is_object()) {
        nlohmann::json kept = nlohmann::json::object();
        for (auto& [key, value] : j.items())
            if (!varies_by_run(key)) kept[key] = without_run_values(value);
        return kept;
    }
    if (j.is_array())
        for (auto& item : j) item = without_run_values(item);
    return j;
}

// report.md of `classify evaluate`: its "(N s)" run time and the table columns in seconds per
// split blanked.
std::string without_report_timings(const std::string& text) {
    std::string out;
    std::vector<bool> timed_columns;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        line = std::regex_replace(line, std::regex(R"(\([0-9.]+ s\))"), "(- s)");
        if (line.rfind("|", 0) != 0) {
            timed_columns.clear();
        } else {
            std::vector<std::string> cells;
            std::istringstream row(line.substr(1));
            for (std::string cell; std::getline(row, cell, '|');) cells.push_back(cell);
            if (timed_columns.empty())
                for (const std::string& cell : cells) timed_columns.push_back(cell.find("s/split") != std::string::npos);
            else if (cells.size() == timed_columns.size() && line.find("---") == std::string::npos)
                for (std::size_t k = 0; k < cells.size(); ++k)
                    if (timed_columns[k]) cells[k] = " - ";
            line = "|";
            for (const std::string& cell : cells) line += cell + "|";
        }
        out += line + "\n";
    }
    return out;
}

// The folder's files by relative path, the folder's own path in them written {out}; JSON files
// reduced as above, the rest byte for byte.
std::map<std::string, std::string> outputs_of(const fs::path& folder) {
    std::map<std::string, std::string> files;
    if (!fs::exists(folder)) return files;
    for (const auto& entry : fs::recursive_directory_iterator(folder)) {
        if (!entry.is_regular_file()) continue;
        std::ifstream in(entry.path(), std::ios::binary);
        // Summaries name the output files, which lie in this run's folder.
        std::string bytes = replaced({std::istreambuf_iterator<char>(in), {}}, folder.string(), "{out}");
        if (entry.path().extension() == ".json") bytes = without_run_values(nlohmann::json::parse(bytes)).dump(1);
        if (entry.path().filename() == "report.md") bytes = without_report_timings(bytes);
        files[fs::relative(entry.path(), folder).string()] = std::move(bytes);
    }
    return files;
}

// stdout with the --json summary's run values removed; a human summary with its run times
// masked as in report.md (the classify commands print "(1.6 s)" and the evaluation table).
std::string comparable_stdout(const std::string& out, const std::string& folder) {
    const std::string text = replaced(out, folder, "{out}");
    if (text.empty() || (text[0] != '{' && text[0] != '[')) return without_report_timings(text);
    return without_run_values(nlohmann::json::parse(text)).dump(1);
}

class Determinism : public testing::TestWithParam<Command> {};

// Moves the second run's allocations elsewhere (no thread cache, small mmap threshold, a padded
// heap top), so that output depending on where objects sit in memory (pointer-keyed sets, CGAL
// handles) differs between the runs and is caught.
class HeapLayout {
public:
    explicit HeapLayout(bool perturbed) : perturbed_(perturbed) {
        if (perturbed_)
            setenv("GLIBC_TUNABLES", "glibc.malloc.tcache_count=0:glibc.malloc.mmap_threshold=4096:glibc.malloc.top_pad=1000000", 1);
    }
    ~HeapLayout() {
        if (perturbed_) unsetenv("GLIBC_TUNABLES");
    }
    HeapLayout(const HeapLayout&) = delete;
    HeapLayout& operator=(const HeapLayout&) = delete;

private:
    bool perturbed_;
};

}  // namespace

TEST_P(Determinism, OneAndTwoThreadsGiveIdenticalOutputs) {
    const Command& c = GetParam();
    const fs::path& in = Inputs::folder();
    TempDir dir;
    std::map<std::string, std::string> files[2];
    std::string out[2];
    for (int threads : {1, 2}) {
        const fs::path folder = dir / ("threads" + std::to_string(threads));
        std::string arguments = replaced(c.arguments, "{in}", in.string());
        arguments = replaced(arguments, "{data}", (test::source_dir() / "data/synthetic").string());
        arguments = replaced(arguments, "{src}", test::source_dir().string());
        arguments = replaced(arguments, "{out}", folder.string());
        if (arguments.find(folder.string() + "/") != std::string::npos) fs::create_directories(folder);
        const HeapLayout layout(threads == 2);
        const auto r = test::run_cli(arguments + " --threads " + std::to_string(threads) + " --log-level error");
        ASSERT_EQ(r.exit_code, 0) << "treelobes " << arguments << "\n" << r.err;
        files[threads - 1] = outputs_of(folder);
        out[threads - 1] = comparable_stdout(r.out, folder.string());
    }
    EXPECT_EQ(out[0], out[1]) << "stdout differs";
    ASSERT_EQ(files[0].size(), files[1].size());
    for (const auto& [name, bytes] : files[0]) {
        ASSERT_TRUE(files[1].count(name)) << name << " only with one thread";
        EXPECT_TRUE(bytes == files[1][name]) << name << " differs between --threads 1 and --threads 2";
    }
}

INSTANTIATE_TEST_SUITE_P(Subcommands, Determinism, testing::ValuesIn(kCommands),
                         [](const auto& param) { return std::string(param.param.name); });
