// Logging and progress on stderr. Data and --json summaries go to stdout or files, never here.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace treelobes {

enum class LogLevel { Error = 0, Warn = 1, Info = 2, Debug = 3 };

void set_log_level(LogLevel level);
LogLevel log_level();
// Parses "error|warn|info|debug"; throws Error(Usage) otherwise.
LogLevel parse_log_level(const std::string& name);

void log_error(const std::string& message);
void log_warn(const std::string& message);
void log_info(const std::string& message);
void log_debug(const std::string& message);

// Progress of a long loop: a redrawn bar on a terminal, a line every few seconds otherwise;
// both show the estimated time left at the pace so far.
// Silent below LogLevel::Info. Not thread-safe: call advance() from one thread.
class Progress {
public:
    Progress(std::string label, std::size_t total);
    ~Progress();
    void advance(std::size_t steps = 1);
    void finish();

private:
    void draw(bool final_line);

    std::string label_;
    std::size_t total_;
    std::size_t done_ = 0;
    bool terminal_;
    bool finished_ = false;
    std::chrono::steady_clock::time_point start_;
    std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace treelobes
