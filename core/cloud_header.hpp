// What a point-cloud file's header says before its points are read: how many points (for the
// memory estimate) and, for LAS/LAZ, the bounds of their coordinates (to pick the neighbouring
// tiles a buffer needs without reading them).
#pragma once

#include "core/cloud_io.hpp"

#include <cstddef>
#include <filesystem>
#include <optional>

namespace treelobes {

// Points of a file as its header states them: LAS/LAZ/COPC (the 64-bit count of LAS 1.4, else
// the legacy one) and PLY (element vertex); for formats without a count (PCD is read by PCL, text
// has no header) the file size over 24 bytes, the shortest usual text row. Throws
// Error(InvalidInput) for a missing file or a LAS/PLY file without a readable header.
std::size_t header_point_count(const std::filesystem::path& path);

// The bounds a LAS/LAZ/COPC header states (original coordinates); nullopt for other formats,
// which have none. Throws Error(InvalidInput) for a missing file or a LAS file without a header.
std::optional<Box3d> header_bounds(const std::filesystem::path& path);

}  // namespace treelobes
