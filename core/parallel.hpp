// The project's parallel loops: TBB's parallel_for, through one door.
//
// Why a door: ThreadSanitizer must know when one thread's work becomes visible to another.
// Debian's libtbb.so is not built with TSan, so the hand-over inside TBB's scheduler (a task is
// spawned, a worker takes it; the worker finishes, the waiting thread goes on) is invisible to it,
// and TSan reported every loop that reads data prepared before the loop, or that the caller reads
// after it, as a race (43 of the 148 tests of the parallel code, none of them real). In a TSan
// build these functions state the two guarantees TBB gives and nothing more:
//   fork: everything the caller did before the loop happens before each task of the loop;
//   join: each task happens before the caller's code after the loop.
// Tasks of one loop get no order among themselves, so a race between two tasks is still reported.
// In every other build they are the plain TBB calls.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#if defined(__SANITIZE_THREAD__)
#define TREELOBES_THREAD_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define TREELOBES_THREAD_SANITIZER 1
#endif
#endif

#ifdef TREELOBES_THREAD_SANITIZER
extern "C" void __tsan_acquire(void* address);
extern "C" void __tsan_release(void* address);
#endif

namespace treelobes {

namespace detail {

#ifdef TREELOBES_THREAD_SANITIZER
// The fork and join edges of one parallel call, as TSan synchronisation objects.
class ForkJoin {
public:
    ForkJoin() { __tsan_release(&fork_); }
    ~ForkJoin() { __tsan_acquire(&join_); }
    ForkJoin(const ForkJoin&) = delete;
    ForkJoin& operator=(const ForkJoin&) = delete;

    template <typename Task>
    auto task(const Task& work) {
        return [this, &work](auto&&... arguments) {
            __tsan_acquire(&fork_);
            work(arguments...);
            __tsan_release(&join_);
        };
    }

private:
    char fork_ = 0;
    char join_ = 0;
};
#else
struct ForkJoin {
    template <typename Task>
    const Task& task(const Task& work) {
        return work;
    }
};
#endif

}  // namespace detail

// body(i) for every i in [first, last), in parallel.
template <typename Index, typename Body>
void parallel_for(Index first, Index last, const Body& body) {
    detail::ForkJoin edges;
    tbb::parallel_for(first, last, edges.task(body));
}

// body(subrange) over subranges of `range` (its grain size bounds how finely it is split).
template <typename Value, typename Body>
void parallel_for(const tbb::blocked_range<Value>& range, const Body& body) {
    detail::ForkJoin edges;
    tbb::parallel_for(range, edges.task(body));
}

// first() and second() at the same time; returns when both have. A parallel loop of two rather
// than tbb::parallel_invoke: the same two tasks, and one kind of TBB bookkeeping for TSan to learn.
template <typename First, typename Second>
void parallel_invoke(const First& first, const Second& second) {
    parallel_for(0, 2, [&](int which) { which == 0 ? first() : second(); });
}

}  // namespace treelobes
