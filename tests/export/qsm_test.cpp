// QSM tables from a skeleton: structure, TreeQSM/CSV round trips, volumes and the tree and
// branch tables; the one QSM reader (core/qsm_io) also serves `eval skeleton`.
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/qsm_io.hpp"
#include "core/skeleton_io.hpp"
#include "export/qsm.hpp"
#include "reconstruct/skeleton_eval.hpp"
#include "sample_trees.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

using namespace treelobes;
using namespace treelobes::exporting;

namespace {

std::vector<int> parents(const QsmModel& m) {
    std::vector<int> p;
    for (const auto& c : m.cylinders) p.push_back(c.parent);
    return p;
}

void expect_same_cylinders(const QsmModel& a, const QsmModel& b, double tolerance) {
    ASSERT_EQ(a.cylinders.size(), b.cylinders.size());
    for (std::size_t i = 0; i < a.cylinders.size(); ++i) {
        const auto &x = a.cylinders[i], &y = b.cylinders[i];
        SCOPED_TRACE("cylinder " + std::to_string(i));
        EXPECT_NEAR(x.radius, y.radius, tolerance);
        EXPECT_NEAR(x.length, y.length, tolerance);
        EXPECT_LT((x.start - y.start).norm(), tolerance);
        EXPECT_LT((x.axis - y.axis).norm(), tolerance);
        EXPECT_EQ(x.parent, y.parent);
        EXPECT_EQ(x.extension, y.extension);
        EXPECT_EQ(x.branch, y.branch);
        EXPECT_EQ(x.branch_order, y.branch_order);
        EXPECT_EQ(x.position_in_branch, y.position_in_branch);
        EXPECT_EQ(x.segment, y.segment);
    }
}

std::map<std::string, double> read_tree_table(const std::filesystem::path& path) {
    std::ifstream in(path);
    std::string header, name, unit;
    std::getline(in, header);
    EXPECT_EQ(header, "quantity\tvalue\tunit");
    std::map<std::string, double> values;
    double value = 0;
    while (in >> name >> value >> unit) values[name] = value;
    return values;
}

}  // namespace

TEST(QsmFromTree, OneCylinderPerInternodeBranchByBranch) {
    const TreeGraph tree = test::sample_tree();
    const QsmModel m = qsm_from_tree(tree);
    ASSERT_EQ(m.cylinders.size(), tree.size() - 1);
    // Trunk (nodes 1-4), upper lateral (9, 10), lower lateral (5-7), its sub-lateral (8).
    EXPECT_EQ(parents(m), (std::vector<int>{-1, 0, 1, 2, 2, 4, 1, 6, 7, 7}));
    const std::vector<int> branch = {0, 0, 0, 0, 1, 1, 2, 2, 2, 3}, order = {0, 0, 0, 0, 1, 1, 1, 1, 1, 2},
                           position = {0, 1, 2, 3, 0, 1, 0, 1, 2, 0}, extension = {1, 2, 3, -1, 5, -1, 7, 8, -1, -1};
    for (std::size_t i = 0; i < m.cylinders.size(); ++i) {
        EXPECT_EQ(m.cylinders[i].branch, branch[i]) << i;
        EXPECT_EQ(m.cylinders[i].branch_order, order[i]) << i;
        EXPECT_EQ(m.cylinders[i].position_in_branch, position[i]) << i;
        EXPECT_EQ(m.cylinders[i].extension, extension[i]) << i;
    }
    // Georeferenced start of the first cylinder, its length and mean radius.
    EXPECT_NEAR((m.cylinders[0].start - tree.origin).norm(), 0.0, 1e-9);
    EXPECT_NEAR(m.cylinders[0].length, 0.75, 1e-6);
    EXPECT_NEAR(m.cylinders[0].radius, 0.11, 1e-6);
    EXPECT_NEAR(m.cylinders[6].radius, 0.04, 1e-6);   // a lateral's first internode: its own radius
    EXPECT_NEAR(m.cylinders[7].radius, 0.035, 1e-6);  // continuation: mean of both ends
    // Every child starts where its parent ends (one cylinder per internode).
    for (const auto& c : m.cylinders) {
        if (c.parent < 0) continue;
        EXPECT_LT((m.cylinders[c.parent].end() - c.start).norm(), 1e-6);
    }
    // Segments split at forks: the trunk's first two internodes, then a new segment after the fork at node 2.
    EXPECT_EQ(m.cylinders[0].segment, m.cylinders[1].segment);
    EXPECT_NE(m.cylinders[1].segment, m.cylinders[2].segment);
    EXPECT_NE(m.cylinders[6].segment, m.cylinders[1].segment);
}

TEST(QsmFromTree, VolumeIsTheSumOfCylinderVolumesAndTablesAgree) {
    const TreeGraph tree = test::sample_tree();
    const QsmModel m = qsm_from_tree(tree);
    double expected = 0, trunk = 0;
    for (const auto& c : m.cylinders) {
        const double v = std::numbers::pi * c.radius * c.radius * c.length;
        expected += v;
        if (c.branch_order == 0) trunk += v;
    }
    const QsmTreeMeasures q = measure_qsm(m);
    EXPECT_NEAR(q.total_volume, expected, 1e-12);
    EXPECT_NEAR(m.volume(), expected, 1e-12);
    EXPECT_NEAR(q.trunk_volume, trunk, 1e-12);
    EXPECT_NEAR(q.trunk_volume + q.branch_volume, q.total_volume, 1e-12);
    EXPECT_NEAR(q.height, 3.0, 1e-5);
    EXPECT_NEAR(q.dbh, 2 * 0.095, 1e-6);  // the trunk internode from 0.75 m to 1.5 m
    EXPECT_EQ(q.branches, 3u);
    EXPECT_EQ(q.max_branch_order, 2);
    EXPECT_NEAR(q.total_length, tree.total_length(), 1e-5);

    test::TempDir dir;
    write_qsm_tree_table(m, dir / "t_tree.txt");
    auto table = read_tree_table(dir / "t_tree.txt");
    EXPECT_NEAR(table["TotalVolume"], expected * 1000.0, 1e-6);  // litres, as TreeQSM
    EXPECT_NEAR(table["TreeHeight"], 3.0, 1e-5);
    EXPECT_NEAR(table["DBHcyl"], 0.19, 1e-6);
    EXPECT_EQ(table["NumberCylinders"], 10);

    write_qsm_branch_table(m, dir / "t_branch.txt");
    std::ifstream in(dir / "t_branch.txt");
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line.rfind("branch\torder\tparent\tvolume_L", 0), 0u);
    double branch_volume_sum = 0;
    int rows = 0;
    while (std::getline(in, line)) {
        std::istringstream row(line);
        int id = 0, order = 0, parent = 0;
        double volume = 0;
        row >> id >> order >> parent >> volume;
        EXPECT_EQ(parent == 0, order == 0) << line;  // only the trunk has no parent branch
        branch_volume_sum += volume;
        ++rows;
    }
    EXPECT_EQ(rows, 4);
    EXPECT_NEAR(branch_volume_sum, expected * 1000.0, 1e-4);
}

TEST(QsmIo, OwnTreeQsmAndCsvRoundTrip) {
    test::TempDir dir;
    const QsmModel m = qsm_from_tree(test::sample_tree());
    write_treeqsm_cylinders(m, dir / "tree.txt");
    EXPECT_EQ(detect_qsm_file(dir / "tree.txt"), QsmFileKind::TreeQsm);
    const QsmModel txt = read_qsm(dir / "tree.txt");
    EXPECT_EQ(txt.format, "treeqsm");
    expect_same_cylinders(m, txt, 1e-6);

    write_qsm_csv(m, dir / "tree.csv");
    std::ifstream in(dir / "tree.csv");
    std::string header;
    std::getline(in, header);
    EXPECT_EQ(header, "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius,length,branchOrder,branchID,segmentID,parentSegmentID");
    EXPECT_EQ(detect_qsm_file(dir / "tree.csv"), QsmFileKind::Csv);
    const QsmModel csv = read_qsm(dir / "tree.csv");
    EXPECT_EQ(csv.format, "csv");
    expect_same_cylinders(m, csv, 1e-6);

    // Same bytes for the same model (deterministic output).
    write_treeqsm_cylinders(txt, dir / "again.txt");
    EXPECT_EQ(read_file(dir / "tree.txt"), read_file(dir / "again.txt"));
}

TEST(QsmIo, EvalReadsOurQsmAsTheSameSkeleton) {
    test::TempDir dir;
    const TreeGraph tree = test::sample_tree();
    write_skeleton_ply(tree, dir / "tree.ply");
    write_qsm_csv(qsm_from_tree(tree), dir / "tree.csv");
    write_treeqsm_cylinders(qsm_from_tree(tree), dir / "tree.txt");
    const SkeletonGraph ours = read_skeleton_graph(dir / "tree.ply");
    for (const char* name : {"tree.csv", "tree.txt"}) {
        const SkeletonGraph qsm = read_skeleton_graph(dir / name);
        EXPECT_EQ(qsm.kind, "treeqsm");
        EXPECT_EQ(qsm.components(), 1u);
        const SkeletonComparison c = compare_skeletons(ours, qsm);
        EXPECT_LT(c.to_reference.max, 1e-3) << name;
        EXPECT_LT(c.from_reference.max, 1e-3) << name;
        ASSERT_TRUE(c.length_ratio);
        EXPECT_NEAR(*c.length_ratio, 1.0, 1e-5);
    }
}

TEST(QsmIo, BadQsmFilesAreInputErrors) {
    test::TempDir dir;
    // Cylinder 1's parent is 2 and 2's parent is 1: a cycle.
    test::write_text(dir / "cycle.txt",
                     "0.1\t1\t0\t0\t0\t0\t0\t1\t2\t0\t0\t0.1\t1\t0\t1\n0.1\t1\t0\t0\t1\t0\t0\t1\t1\t0\t0\t0.1\t1\t0\t2\n");
    EXPECT_EQ(test::error_code_of([&] { read_qsm(dir / "cycle.txt"); }), ExitCode::InvalidInput);
    test::write_text(dir / "parent.txt", "0.1\t1\t0\t0\t0\t0\t0\t1\t7\t0\t0\t0.1\t1\t0\t1\n");
    EXPECT_EQ(test::error_code_of([&] { read_qsm(dir / "parent.txt"); }), ExitCode::InvalidInput);
    test::write_text(dir / "short.txt", "0.1\t1\t0\t0\t0\t0\t0\t1\t0\t0\t0\t0.1\t1\t0\t1\n0.1\t1\t0\n");
    EXPECT_EQ(test::error_code_of([&] { read_qsm(dir / "short.txt"); }), ExitCode::InvalidInput);
    test::write_text(dir / "header.csv", "a,b,c\n1,2,3\n");
    EXPECT_EQ(detect_qsm_file(dir / "header.csv"), QsmFileKind::None);
    EXPECT_EQ(test::error_code_of([&] { read_qsm(dir / "header.csv"); }), ExitCode::InvalidInput);
    test::write_text(dir / "missing.csv", "ID,parentID,startX,startY,startZ,endX,endY,endZ,radius,length,branchOrder,branchID,segmentID\n");
    EXPECT_EQ(detect_qsm_file(dir / "missing.csv"), QsmFileKind::None);
    EXPECT_EQ(test::error_code_of([&] { read_qsm(dir / "nothing.txt"); }), ExitCode::InvalidInput);
}

// Found by the 60-second fuzz runs with seed 1: a CSV header naming columns twice let rows
// through that were narrower than the columns read from them (heap-buffer-overflow under ASan).
TEST(QsmIo, CsvHeaderNamingAColumnTwiceIsBadInputNotAnOverflow) {
    EXPECT_EQ(test::error_code_of([&] { read_qsm(test::source_dir() / "tests/data/fuzz/qsm_csv_column_named_twice.csv"); }),
              ExitCode::InvalidInput);
}
