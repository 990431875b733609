// Runs the official validators installed by scripts/setup.sh under tools/validators (npm ci):
// the Khronos glTF-Validator and ajv with the CityJSON schemas. A test that needs them fails
// with a message saying how to install them when they are missing.
#pragma once

#include <filesystem>
#include <string>

namespace treelobes::test {

struct ValidatorRun {
    bool available = false;  // node and the npm packages were found
    int exit_code = -1;      // of the validator script: 0 valid, 1 invalid, 2 unreadable
    std::string output;      // its stdout and stderr
};

// tools/validators/validate_gltf.js FILE
ValidatorRun validate_gltf(const std::filesystem::path& file);
// tools/validators/validate_cityjson.js ../shared/schemas/cityjson-2.0.2 FILE
ValidatorRun validate_cityjson(const std::filesystem::path& file);
// The official CityJSON 2.0.2 schemas: $TREELOBES_CITYJSON_SCHEMAS or
// ../shared/schemas/cityjson-2.0.2 beside the source tree.
std::filesystem::path cityjson_schema_dir();

}  // namespace treelobes::test
