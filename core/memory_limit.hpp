// Refusing inputs that cannot fit in memory before anything is allocated: a header that
// promises more points than the machine holds is reported with the estimate, instead of the
// reader being killed by the kernel half-way through (or a batch losing every other tree).
#pragma once

#include <cstdint>
#include <string>

namespace treelobes {

// Bytes the readers may plan for: the physical memory of the machine, or TREELOBES_MAX_MEMORY
// (a byte count with an optional K, M or G suffix, powers of 1024) when that is set and smaller.
std::uint64_t memory_limit();

// Throws Error(InvalidInput) "<file>: <what> needs about N GiB of memory, more than the M GiB
// this machine has (...)" when `bytes` exceeds memory_limit().
void check_memory_estimate(std::uint64_t bytes, const std::string& file, const std::string& what);

}  // namespace treelobes
