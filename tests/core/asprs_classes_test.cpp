// ASPRS classes (core/asprs_classes.hpp): which can never hold a tree's points, and their names.
#include "core/asprs_classes.hpp"

#include <gtest/gtest.h>

namespace treelobes {
namespace {

TEST(AsprsClasses, BuildingsWaterWiresAndNoiseAreNoTrees) {
    for (int code : {6, 7, 9, 10, 11, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22})
        EXPECT_TRUE(asprs_never_a_tree(static_cast<std::uint8_t>(code))) << code;
    for (int code : {0, 1, 2, 3, 4, 5, 8, 12, 23, 64, 255}) EXPECT_FALSE(asprs_never_a_tree(static_cast<std::uint8_t>(code))) << code;
}

TEST(AsprsClasses, Names) {
    EXPECT_EQ(asprs_class_name(5), "high vegetation");
    EXPECT_EQ(asprs_class_name(6), "building");
    EXPECT_EQ(asprs_class_name(14), "wire conductor");
    EXPECT_EQ(asprs_class_name(22), "temporal exclusion");
    EXPECT_EQ(asprs_class_name(8), "class 8");  // reserved in LAS 1.4
    EXPECT_EQ(asprs_class_name(200), "class 200");
}

}  // namespace
}  // namespace treelobes
