// Numbers that command summaries (JSON and text) report.
#pragma once

namespace treelobes::cli {

// Rounded for readable JSON (floats would print as 0.30000001192092896).
double rounded(double value, int digits = 4);

// Peak resident memory of this process so far, in MB.
double peak_memory_mb();

}  // namespace treelobes::cli
