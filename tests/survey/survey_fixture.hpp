// A small synthetic survey (tiles side by side from `treelobes synth tile`) and the checks the
// survey tests share: running the CLI through a shell and comparing merged outputs byte by byte.
#pragma once

#include <filesystem>
#include <string>

namespace treelobes::test {

// Path of the treelobes binary, single-quoted for a shell command line.
std::string cli();

// `count` tiles of `size` m on a row, `trees` trees each, in `dir`/tiles/t_<i>.las; made once per
// (dir, ...) call. Returns the tiles folder.
std::filesystem::path make_survey(const std::filesystem::path& dir, int count, int trees, double size);

// Runs `command` with sh -c; returns the exit code (128 + signal when killed).
int shell(const std::string& command);

// The tile options of every batch in these tests (input segmentation: fast and deterministic).
inline const char* kTileOptions = "--use-input-segmentation --map-size 200";

std::string file_bytes(const std::filesystem::path& path);

// Fails the test unless both merge outputs hold the same bytes in each merged file.
void expect_same_merge(const std::filesystem::path& a, const std::filesystem::path& b);

}  // namespace treelobes::test
