// Point samples of a triangle mesh, each labelled wood or leaf: the "scan" of a CG tree model
// that `treelobes rebuild` reconstructs (Livny et al. 2011, §7: Xfrog models sampled into points).
//
//   uniform  area-weighted uniform samples on the surface: a face is chosen with probability
//            proportional to its area, a point on it uniformly (square-root barycentrics). Every
//            surface is seen, the inner crown and the far side included.
//   tls      the terrestrial scanner of synth/scanner.hpp from `stations` tripods around the
//            model (occlusion, beam, range noise); the angular step is chosen from the model's
//            size so that about `samples` points come back.
//   als      the airborne scanner from above (strips, multiple returns); the pulse density is
//            chosen the same way.
// Scans that return more than `samples` points are thinned to `samples` by a seeded random
// choice (in scan order). Output: the mesh's origin, positions in its frame, classification 5
// and the extra attribute `wood` (uint8: 1 wood, 0 leaf). The same mesh, labels, options and
// seed give the same cloud for any thread count.
#pragma once

#include "core/point_cloud.hpp"
#include "core/triangle_mesh.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace treelobes::synth {

enum class SamplePattern { Uniform, Tls, Als };

// "uniform", "tls", "als"; Error(Usage) otherwise.
SamplePattern parse_sample_pattern(const std::string& name);
const char* sample_pattern_name(SamplePattern pattern);

struct MeshSamplingOptions {
    SamplePattern pattern = SamplePattern::Uniform;
    std::size_t samples = 200000;  // points wanted (uniform: exactly; scans: at most, about this many)
    double density = 0;            // points per m^2 of surface instead of `samples` (uniform only; 0 = off)
    int stations = 4;              // tls: tripods evenly around the model
    std::uint64_t seed = 1;
};

struct MeshSamplingReport {
    double surface_area = 0;  // m^2 of all faces
    std::size_t wood_points = 0, leaf_points = 0;
    std::uint64_t pulses = 0;        // scans
    std::size_t scanned_points = 0;  // scans, before thinning to `samples`
    double angular_step_deg = 0;     // tls
    double pulse_density = 0;        // als, per m^2
};

// `wood`: one label per face (1 wood, 0 leaf). Throws Error(InvalidInput) for a mesh without
// faces or surface, Error(Usage) for options out of range.
PointCloud sample_mesh(const TriangleMesh& mesh, const std::vector<std::uint8_t>& wood, const MeshSamplingOptions& options,
                       MeshSamplingReport* report = nullptr);

// Area-weighted uniform samples alone (also used to compare surfaces): `count` points.
PointCloud sample_surface(const TriangleMesh& mesh, const std::vector<std::uint8_t>& wood, std::size_t count, std::uint64_t seed);

}  // namespace treelobes::synth
