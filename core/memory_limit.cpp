#include "core/memory_limit.hpp"

#include "core/error.hpp"

#include <unistd.h>

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace treelobes {
namespace {

std::uint64_t physical_memory() {
    const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page_size <= 0) return UINT64_MAX;  // unknown: no limit from the machine
    return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
}

// "512M" -> 536870912; throws Error(Usage) naming the variable for anything else.
std::uint64_t parse_byte_count(std::string_view text) {
    std::uint64_t value = 0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    const std::string_view suffix(end, static_cast<std::size_t>(text.data() + text.size() - end));
    int shift = -1;
    if (suffix.empty()) shift = 0;
    else if (suffix == "K" || suffix == "k") shift = 10;
    else if (suffix == "M" || suffix == "m") shift = 20;
    else if (suffix == "G" || suffix == "g") shift = 30;
    if (error != std::errc() || end == text.data() || shift < 0 || value > (UINT64_MAX >> shift))
        throw Error::usage("TREELOBES_MAX_MEMORY='" + std::string(text) + "' is not a byte count such as 4G, 512M or 1000000");
    return value << shift;
}

std::string gibibytes(std::uint64_t bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g GiB", static_cast<double>(bytes) / (1024.0 * 1024.0 * 1024.0));
    return text;
}

}  // namespace

std::uint64_t memory_limit() {
    std::uint64_t limit = physical_memory();
    if (const char* env = std::getenv("TREELOBES_MAX_MEMORY"); env && *env) limit = std::min(limit, parse_byte_count(env));
    return limit;
}

void check_memory_estimate(std::uint64_t bytes, const std::string& file, const std::string& what) {
    const std::uint64_t limit = memory_limit();
    if (bytes <= limit) return;
    const bool capped = std::getenv("TREELOBES_MAX_MEMORY") && limit < physical_memory();
    throw Error::input(file, what + " needs about " + gibibytes(bytes) + " of memory, more than the " + gibibytes(limit) +
                                 (capped ? " TREELOBES_MAX_MEMORY allows" : " this machine has") +
                                 "; split the file into tiles (e.g. `pdal tile`) or thin it first");
}

}  // namespace treelobes
