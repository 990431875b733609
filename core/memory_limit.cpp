#include "core/memory_limit.hpp"

#include "core/error.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace treelobes {
namespace {

std::uint64_t physical_memory() {
    const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page_size <= 0) return UINT64_MAX;  // unknown: no limit from the machine
    return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
}

std::string gibibytes(double bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g GiB", bytes / (1024.0 * 1024.0 * 1024.0));
    return text;
}

}  // namespace

double parse_memory_size(const std::string& text, const std::string& setting) {
    double value = 0;
    char unit = 0;
    char rest = 0;
    const int fields = std::sscanf(text.c_str(), "%lf%c%c", &value, &unit, &rest);
    double factor = 1;
    if (fields == 2) {
        switch (unit) {
            case 'k':
            case 'K':
                factor = 1024.0;
                break;
            case 'm':
            case 'M':
                factor = 1024.0 * 1024;
                break;
            case 'g':
            case 'G':
                factor = 1024.0 * 1024 * 1024;
                break;
            case 't':
            case 'T':
                factor = 1024.0 * 1024 * 1024 * 1024;
                break;
            default:
                factor = 0;
        }
    }
    if (fields < 1 || fields > 2 || factor == 0 || !std::isfinite(value) || value <= 0 || value * factor > 1.8e19)
        throw Error::usage(setting + " '" + text + "': expected a size such as 512M, 8G or a number of bytes");
    return value * factor;
}

std::uint64_t memory_limit() {
    std::uint64_t limit = physical_memory();
    if (const char* env = std::getenv("TREELOBES_MAX_MEMORY"); env && *env)
        limit = std::min(limit, static_cast<std::uint64_t>(parse_memory_size(env, "TREELOBES_MAX_MEMORY")));
    return limit;
}

double default_memory_budget_bytes() { return 0.5 * static_cast<double>(memory_limit()); }

void check_memory_estimate(std::uint64_t bytes, const std::string& file, const std::string& what) {
    const std::uint64_t limit = memory_limit();
    if (bytes <= limit) return;
    const bool capped = std::getenv("TREELOBES_MAX_MEMORY") && limit < physical_memory();
    throw Error::input(file, what + " needs about " + gibibytes(static_cast<double>(bytes)) + " of memory, more than the " +
                                     gibibytes(static_cast<double>(limit)) +
                                     (capped ? " TREELOBES_MAX_MEMORY allows" : " this machine has") +
                                     "; split the file into tiles (`treelobes retile --size METRES`) or thin it first");
}

std::optional<std::string> memory_refusal(std::size_t points, double bytes_per_point, double budget_bytes) {
    const double estimate = static_cast<double>(points) * bytes_per_point;
    if (estimate <= budget_bytes) return std::nullopt;
    char message[512];
    std::snprintf(message, sizeof message,
                  "%zu points need about %.1f GiB (%.0f bytes per point), more than the memory budget of %.1f GiB: "
                  "cut it with `treelobes retile --size METRES` into smaller tiles, or raise --max-memory",
                  points, estimate / (1024.0 * 1024 * 1024), bytes_per_point, budget_bytes / (1024.0 * 1024 * 1024));
    return std::string(message);
}

}  // namespace treelobes
