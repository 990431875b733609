// Quantitative structure models (QSM): a tree as a list of cylinders, the exchange format of
// TreeQSM (Raumonen et al. 2013), SimpleForest, aRchi and rTwig. Two text forms:
//
//   TreeQSM cylinder table  no header, one cylinder per line, tab separated (whitespace, commas
//     or semicolons are read too), 15 columns: radius, length, start x y z, axis x y z, parent,
//     extension, added, unmodified radius, branch, branch order, position in branch. Parent and
//     extension are 1-based row numbers (0 = none), branch 1-based, position in branch 1-based,
//     branch order 0 on the trunk. Tables with 8 to 14 columns are read too (missing columns
//     take defaults: no parent, order 0).
//   SimpleForest / rTwig CSV  a header line with exactly
//     ID,parentID,startX,startY,startZ,endX,endY,endZ,radius,length,branchOrder,branchID,segmentID,parentSegmentID
//     (columns may come in any order; extra columns are ignored). IDs are arbitrary integers;
//     a parentID that names no row means "no parent" (we write -1).
//
// Coordinates are metres in the file's frame (georeferenced QSMs keep their large values;
// they are held in double).
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace treelobes {

struct QsmCylinder {
    double radius = 0;
    double length = 0;
    Eigen::Vector3d start{0, 0, 0};
    Eigen::Vector3d axis{0, 0, 1};  // unit vector
    int parent = -1;                // 0-based index of the parent cylinder, -1 for none
    int extension = -1;             // 0-based index of the cylinder continuing this one, -1 for none
    bool added = false;             // TreeQSM: filled in, not fitted
    double unmodified_radius = 0;
    int branch = 0;              // 0-based branch (axis) index
    int branch_order = 0;        // 0 on the trunk
    int position_in_branch = 0;  // 0-based position along the branch
    int segment = 0;             // 0-based segment (run between forks): CSV only, derived otherwise

    Eigen::Vector3d end() const { return start + axis * length; }
    double volume() const;  // pi r^2 l, cubic metres
};

struct QsmModel {
    std::vector<QsmCylinder> cylinders;
    std::string format;  // "treeqsm" or "csv" for a model read from a file

    double volume() const;        // sum of cylinder volumes (cubic metres)
    double total_length() const;  // sum of cylinder lengths (metres)
    // Fills `segment` from parents and extensions: a segment is a run of cylinders joined by
    // extensions without a lateral child leaving in between (a new segment starts at each
    // cylinder that is not its parent's extension and after each fork).
    void derive_segments();
    // Throws Error(InvalidInput) naming `name` when a parent/extension index is out of range,
    // a cylinder is its own parent, parents form a cycle, or a value is not finite / negative.
    void validate(const std::string& name) const;
};

enum class QsmFileKind { None, TreeQsm, Csv };

// What the first data line of a text file looks like: a SimpleForest/rTwig header, a numeric
// row of at least 8 columns (TreeQSM), or neither. Reads at most the first few lines.
// `columns` receives the number of columns of that line.
QsmFileKind detect_qsm_file(const std::filesystem::path& path, std::size_t* columns = nullptr);

// Reads either form (detected as above). Throws Error(InvalidInput) naming the file, the line
// and what was expected.
QsmModel read_qsm(const std::filesystem::path& path);

// Written atomically and deterministically (fixed digits). The TreeQSM table has all 15 columns.
void write_treeqsm_cylinders(const QsmModel& model, const std::filesystem::path& path);
void write_qsm_csv(const QsmModel& model, const std::filesystem::path& path);

}  // namespace treelobes
