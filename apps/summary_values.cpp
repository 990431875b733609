#include "apps/summary_values.hpp"

#include <sys/resource.h>

#include <cmath>
#include <cstdio>

namespace treelobes::cli {

double rounded(double value, int digits) {
    const double scale = std::pow(10.0, digits);
    return std::round(value * scale) / scale;
}

double peak_memory_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports kilobytes
}

double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double lap_seconds(std::chrono::steady_clock::time_point& mark) {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - mark).count();
    mark = now;
    return seconds;
}

std::string format_numbers(const char* pattern, double a, double b, double c) {
    char text[256];
    std::snprintf(text, sizeof text, pattern, a, b, c);
    return text;
}

}  // namespace treelobes::cli
