// Atomic output: every writer of the project goes through write_atomically so a failure
// (or an interrupted run) never leaves a half-written file at the destination.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace treelobes {

// Opens "<path>.tmp.<pid>" in binary mode, calls `write`, flushes, checks the stream and
// renames onto `path`. Throws Error(InvalidInput) naming the path when the directory does
// not exist or is not writable; the temporary file is removed on any failure.
void write_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

// For libraries that only write to a file name (PCL, OpenMesh): `write` receives the temporary
// path (same folder and extension as `path`) and must create that file.
void write_atomically_via_path(const std::filesystem::path& path, const std::function<void(const std::filesystem::path& temporary)>& write);

// Convenience for small text or binary payloads.
void write_file_atomically(const std::filesystem::path& path, const std::string& contents);

// Reads a whole file; throws Error(InvalidInput) when it is missing, a directory or unreadable.
std::string read_file(const std::filesystem::path& path);

}  // namespace treelobes
