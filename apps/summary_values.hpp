// Numbers that command summaries (JSON and text) report.
#pragma once

#include <chrono>
#include <string>

namespace treelobes::cli {

// Rounded for readable JSON (floats would print as 0.30000001192092896).
double rounded(double value, int digits = 4);

// Peak resident memory of this process so far, in MB.
double peak_memory_mb();

// Seconds from `start` to now, on the steady clock.
double seconds_since(std::chrono::steady_clock::time_point start);

// Seconds from `mark` to now; moves `mark` to now, so consecutive calls time consecutive stages.
double lap_seconds(std::chrono::steady_clock::time_point& mark);

// A printf pattern of up to three numbers as a string, for the human-readable summary lines.
std::string format_numbers(const char* pattern, double a, double b = 0, double c = 0);

}  // namespace treelobes::cli
