#include "core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

using namespace treelobes;

TEST(Parallel, EveryIndexOnceAndEverySubrangeOnce) {
    std::vector<std::atomic<int>> by_index(1000);
    treelobes::parallel_for(std::size_t{0}, by_index.size(), [&](std::size_t i) { ++by_index[i]; });
    for (const auto& count : by_index) EXPECT_EQ(count.load(), 1);

    std::vector<std::atomic<int>> by_range(1000);
    treelobes::parallel_for(tbb::blocked_range<std::size_t>(0, by_range.size(), 7), [&](const tbb::blocked_range<std::size_t>& range) {
        EXPECT_GE(range.size(), 1u);
        for (std::size_t i = range.begin(); i < range.end(); ++i) ++by_range[i];
    });
    for (const auto& count : by_range) EXPECT_EQ(count.load(), 1);
}

TEST(Parallel, InvokeRunsBothOnceAndReturnsAfterBoth) {
    int first = 0, second = 0;
    treelobes::parallel_invoke([&] { ++first; }, [&] { ++second; });
    EXPECT_EQ(first, 1);
    EXPECT_EQ(second, 1);
}

TEST(Parallel, AnExceptionOfATaskReachesTheCaller) {
    EXPECT_THROW(treelobes::parallel_for(0, 100,
                                         [](int i) {
                                             if (i == 42) throw std::runtime_error("task 42");
                                         }),
                 std::runtime_error);
}
