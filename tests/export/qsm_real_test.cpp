// The aRchi TreeQSM cylinder table (../shared/data/archi) read by the one QSM reader, written
// back in both forms and read again.
#include "core/qsm_io.hpp"
#include "export/qsm.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

using namespace treelobes;

TEST(QsmReal, ArchiTreeQsmReadsAndRoundTrips) {
    const auto file = test::real_data("archi/tree1_treeqsm_cylinders.txt");
    const QsmModel m = read_qsm(file);
    ASSERT_EQ(m.cylinders.size(), 2271u);
    EXPECT_EQ(m.format, "treeqsm");
    const QsmCylinder& first = m.cylinders.front();
    EXPECT_NEAR(first.radius, 0.2469613, 1e-9);
    EXPECT_NEAR(first.length, 1.618988, 1e-9);
    EXPECT_NEAR(first.start.x(), 4.251252, 1e-9);
    EXPECT_EQ(first.parent, -1);
    EXPECT_EQ(first.extension, 1);
    EXPECT_EQ(first.branch, 0);
    EXPECT_EQ(first.branch_order, 0);
    EXPECT_EQ(m.cylinders[1].parent, 0);
    EXPECT_EQ(m.cylinders[1].position_in_branch, 1);
    // The table's row 100 (index 99) starts branch 2 with parent row 99 (TreeQSM counts from 1).
    EXPECT_EQ(m.cylinders[99].branch, 1);
    EXPECT_EQ(m.cylinders[99].branch_order, 1);
    EXPECT_EQ(m.cylinders[99].parent, 98);
    double volume = 0;
    for (const auto& c : m.cylinders) volume += c.volume();
    EXPECT_NEAR(exporting::measure_qsm(m).total_volume, volume, 1e-9);
    EXPECT_GT(exporting::measure_qsm(m).dbh, 0.2);

    test::TempDir dir;
    write_treeqsm_cylinders(m, dir / "archi.txt");
    write_qsm_csv(m, dir / "archi.csv");
    for (const char* name : {"archi.txt", "archi.csv"}) {
        const QsmModel back = read_qsm(dir / name);
        ASSERT_EQ(back.cylinders.size(), m.cylinders.size()) << name;
        for (std::size_t i = 0; i < m.cylinders.size(); ++i) {
            const auto &a = m.cylinders[i], &b = back.cylinders[i];
            ASSERT_NEAR(a.radius, b.radius, 1e-7) << name << " " << i;
            ASSERT_NEAR(a.length, b.length, 1e-6) << name << " " << i;
            ASSERT_LT((a.start - b.start).norm(), 1e-6) << name << " " << i;
            ASSERT_EQ(a.parent, b.parent) << name << " " << i;
            ASSERT_EQ(a.branch_order, b.branch_order) << name << " " << i;
            ASSERT_EQ(a.segment, b.segment) << name << " " << i;
        }
    }
}
