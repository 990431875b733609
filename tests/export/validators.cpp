#include "validators.hpp"

#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace treelobes::test {

namespace {

fs::path validators_dir() { return source_dir() / "tools" / "validators"; }

bool validators_installed(const std::string& package) {
    if (fs::exists(validators_dir() / "node_modules" / package / "package.json") && std::system("node --version >/dev/null 2>&1") == 0)
        return true;
    ADD_FAILURE() << "validator '" << package << "' is not installed under " << validators_dir()
                  << "/node_modules (or node is missing): run scripts/setup.sh, or `npm ci` in tools/validators";
    return false;
}

ValidatorRun run_node(const std::string& script, const std::string& arguments, const std::string& package) {
    ValidatorRun run;
    if (!(run.available = validators_installed(package))) return run;
    const std::string command = "node " + quoted(validators_dir() / script) + " " + arguments + " 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    if (!pipe) return run;
    std::array<char, 4096> buffer{};
    while (std::fgets(buffer.data(), buffer.size(), pipe)) run.output += buffer.data();
    const int status = pclose(pipe);
    run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return run;
}

}  // namespace

fs::path cityjson_schema_dir() {
    if (const char* dir = std::getenv("TREELOBES_CITYJSON_SCHEMAS")) return dir;
    return (source_dir() / ".." / "shared" / "schemas" / "cityjson-2.0.2").lexically_normal();
}

ValidatorRun validate_gltf(const fs::path& file) { return run_node("validate_gltf.js", quoted(file), "gltf-validator"); }

ValidatorRun validate_cityjson(const fs::path& file) {
    const fs::path schemas = cityjson_schema_dir();
    if (!fs::exists(schemas / "cityjson.schema.json")) {
        ADD_FAILURE() << "CityJSON 2.0.2 schemas not found in " << schemas;
        return {};
    }
    return run_node("validate_cityjson.js", quoted(schemas) + " " + quoted(file), "ajv");
}

}  // namespace treelobes::test
