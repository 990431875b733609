#include "core/log.hpp"

#include "core/error.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <unistd.h>

namespace treelobes {

namespace {

LogLevel g_level = LogLevel::Info;

void emit(LogLevel level, const char* tag, const std::string& message) {
    if (static_cast<int>(level) > static_cast<int>(g_level)) return;
    std::cerr << "treelobes: " << tag << message << "\n";
}

}  // namespace

void set_log_level(LogLevel level) { g_level = level; }
LogLevel log_level() { return g_level; }

LogLevel parse_log_level(const std::string& name) {
    if (name == "error") return LogLevel::Error;
    if (name == "warn") return LogLevel::Warn;
    if (name == "info") return LogLevel::Info;
    if (name == "debug") return LogLevel::Debug;
    throw Error::usage("--log-level: expected error, warn, info or debug, got '" + name + "'");
}

void log_error(const std::string& message) { emit(LogLevel::Error, "error: ", message); }
void log_warn(const std::string& message) { emit(LogLevel::Warn, "warning: ", message); }
void log_info(const std::string& message) { emit(LogLevel::Info, "", message); }
void log_debug(const std::string& message) { emit(LogLevel::Debug, "debug: ", message); }

Progress::Progress(std::string label, std::size_t total)
        : label_(std::move(label)),
          total_(total),
          terminal_(::isatty(STDERR_FILENO) != 0),
          start_(std::chrono::steady_clock::now()),
          last_draw_(start_) {}

Progress::~Progress() {
    if (!finished_ && done_ > 0) finish();
}

void Progress::advance(std::size_t steps) {
    done_ += steps;
    const auto now = std::chrono::steady_clock::now();
    // A terminal bar is redrawn at most 10 times a second; log files get a line every 5 s.
    const auto interval = terminal_ ? std::chrono::milliseconds(100) : std::chrono::milliseconds(5000);
    if (now - last_draw_ >= interval) {
        last_draw_ = now;
        draw(false);
    }
}

void Progress::finish() {
    finished_ = true;
    draw(true);
}

void Progress::draw(bool final_line) {
    if (static_cast<int>(log_level()) < static_cast<int>(LogLevel::Info)) return;
    const double fraction = total_ ? static_cast<double>(done_) / static_cast<double>(total_) : 1.0;
    // Remaining time at the mean pace so far; none before the first step or after the last.
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::string eta;
    if (done_ > 0 && done_ < total_) {
        const long remaining = std::lround(elapsed / static_cast<double>(done_) * static_cast<double>(total_ - done_));
        char text[40];
        std::snprintf(text, sizeof text, ", ETA %ld:%02ld", remaining / 60, remaining % 60);
        eta = text;
    }
    if (terminal_) {
        const int width = 30, filled = static_cast<int>(fraction * width);
        std::fprintf(stderr, "\r%s [%s%s] %zu/%zu%s   ", label_.c_str(), std::string(filled, '#').c_str(),
                     std::string(width - filled, ' ').c_str(), done_, total_, eta.c_str());
        if (final_line) std::fputc('\n', stderr);
    } else if (final_line || done_ < total_) {
        std::fprintf(stderr, "treelobes: %s %zu/%zu (%.0f%%%s)\n", label_.c_str(), done_, total_, 100.0 * fraction, eta.c_str());
    }
    std::fflush(stderr);
}

}  // namespace treelobes
