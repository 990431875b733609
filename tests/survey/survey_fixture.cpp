#include "survey_fixture.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace treelobes::test {

std::string cli() { return std::string("'") + TREELOBES_CLI + "'"; }

int shell(const std::string& command) {
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

fs::path make_survey(const fs::path& dir, int count, int trees, double size) {
    const fs::path tiles = dir / "tiles";
    fs::create_directories(tiles);
    for (int i = 0; i < count; ++i) {
        const fs::path synth = dir / ("synth_" + std::to_string(i));
        const std::string command = cli() + " --log-level warn synth tile --trees " + std::to_string(trees) + " --size " +
                                    std::to_string(size) + " --seed " + std::to_string(40 + i) +
                                    " --pulse-density 20 --max-leaves 2000 --origin " + std::to_string(500000 + i * size) +
                                    " 5400000 300 --out '" + synth.string() + "' >/dev/null";
        EXPECT_EQ(shell(command), 0) << command;
        fs::rename(synth / "tile.las", tiles / ("t_" + std::to_string(i) + ".las"));
        fs::remove_all(synth);
    }
    return tiles;
}

std::string file_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

void expect_same_merge(const fs::path& a, const fs::path& b) {
    for (const char* name : {"trees.csv", "trees.geojson", "crowns.geojson", "survey.forest", "summary.json"}) {
        ASSERT_TRUE(fs::exists(a / name)) << a / name;
        ASSERT_TRUE(fs::exists(b / name)) << b / name;
        EXPECT_TRUE(file_bytes(a / name) == file_bytes(b / name)) << name << " differs between " << a << " and " << b;
    }
}

}  // namespace treelobes::test
