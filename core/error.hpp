// treelobes::Error — the one exception type that crosses stage boundaries.
//
// Thrown where bad input is detected, it carries the exit code the CLI must use
// (DESIGN.md "User-facing conventions") and a one-line message naming the file,
// the position and what was expected.
#pragma once

#include <stdexcept>
#include <string>

namespace treelobes {

enum class ExitCode : int {
    Ok = 0,
    Usage = 1,           // bad flags, bad configuration values
    InvalidInput = 2,    // unreadable, truncated or malformed input
    PartialFailure = 3,  // batch finished but some items failed
    Internal = 4,        // a bug: should never happen
};

class Error : public std::runtime_error {
public:
    Error(ExitCode code, const std::string& message) : std::runtime_error(message), code_(code) {}

    ExitCode code() const noexcept { return code_; }

    // "<file>: <what>" — unreadable or malformed input (exit 2).
    static Error input(const std::string& file, const std::string& what) {
        return {ExitCode::InvalidInput, file.empty() ? what : file + ": " + what};
    }
    // Bad option or configuration value (exit 1).
    static Error usage(const std::string& what) { return {ExitCode::Usage, what}; }

private:
    ExitCode code_;
};

}  // namespace treelobes
