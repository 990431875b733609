// Built and run only under ThreadSanitizer (scripts/sanitize.sh tsan): the tasks of one loop add
// to one plain counter without a lock, a race TSan must report. It proves that the fork/join edges
// of core/parallel.hpp and the suppressions of scripts/tsan.supp leave a race between two tasks of
// a loop visible.
#include "core/parallel.hpp"

#include <chrono>
#include <cstdio>
#include <thread>

int main() {
    long counter = 0;
    treelobes::parallel_for(tbb::blocked_range<int>(0, 64, 1), [&](const tbb::blocked_range<int>& range) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));  // so that both threads take tasks
        counter += range.size();
    });
    std::printf("counter %ld\n", counter);
    return 0;
}
