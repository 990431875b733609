#include "lobes/tlobe_io.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "geometry/alpha_shape.hpp"
#include "geometry/polyline.hpp"
#include "lobes/mesh_coder.hpp"
#include "lobes/occupancy.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <optional>
#include <span>

namespace treelobes::lobes {

namespace {

constexpr std::array<char, 4> kMagic{'T', 'L', 'O', 'B'};
constexpr std::size_t kHeaderSize = 20;
constexpr std::size_t kMaxPayload = std::size_t{1} << 30;  // 1 GiB: anything larger is not a .tlobe
constexpr double kMaxLeafArea = 1e7;                       // m^2: a tree with more leaf area than 10 km^2 is a corrupt field
// Deflate cannot expand data by more than about 1032:1 (zlib's technical details), so a
// header claiming more is refused before the payload buffer is allocated.
constexpr std::uint64_t kMaxInflateRatio = 1032;

void put_u32(std::string& s, std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) s[at + i] = static_cast<char>(v >> (8 * i));
}

std::uint32_t get_u32(std::string_view s, std::size_t at) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + i])) << (8 * i);
    return v;
}

// CRC-32 of the header without its CRC field, then of the compressed payload.
std::uint32_t file_crc(std::string_view file) {
    uLong crc = crc32(0L, Z_NULL, 0);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(file.data()), 16);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(file.data() + kHeaderSize), static_cast<uInt>(file.size() - kHeaderSize));
    return static_cast<std::uint32_t>(crc);
}

void encode_skeleton(const TreeGraph& skeleton, const TlobeOptions& o, ByteWriter& out) {
    out.varint(skeleton.size());
    std::vector<std::array<std::int64_t, 3>> q(skeleton.size());
    for (std::size_t i = 0; i < skeleton.size(); ++i) {
        const TreeNode& node = skeleton.nodes[i];
        for (int k = 0; k < 3; ++k) q[i][k] = quantize(node.position[k], o.quantum);
        if (i > 0) out.varint(i - static_cast<std::size_t>(node.parent));
        for (int k = 0; k < 3; ++k) out.svarint(q[i][k] - (i > 0 ? q[node.parent][k] : 0));
        out.varint(static_cast<std::uint64_t>(quantize(2.0 * node.radius, o.diameter_quantum)));
    }
}

TreeGraph decode_skeleton(ByteReader& in, double quantum, double diameter_quantum) {
    TreeGraph skeleton;
    const std::size_t n = in.count(4, "skeleton node count");
    if (n == 0) in.fail("the skeleton has no root");
    std::vector<std::array<std::int64_t, 3>> q(n);
    for (std::size_t i = 0; i < n; ++i) {
        int parent = -1;
        if (i > 0) {
            const std::uint64_t delta = in.varint();
            if (delta == 0 || delta > i) in.fail("skeleton node with an invalid parent");
            parent = static_cast<int>(i - delta);
        }
        Eigen::Vector3f p;
        for (int k = 0; k < 3; ++k) {
            q[i][k] = in.delta_coordinate(parent >= 0 ? q[parent][k] : 0);
            p[k] = static_cast<float>(static_cast<double>(q[i][k]) * quantum);
        }
        const double diameter = static_cast<double>(in.varint()) * diameter_quantum;
        skeleton.add_node(p, static_cast<float>(diameter / 2), parent);
    }
    return skeleton;
}

// Which nodes of the main skeleton a file keeps: Douglas-Peucker along each chain (root, forks,
// tips and lobe seeds kept), a dropped node within skeleton_tolerance of the segment between the
// kept nodes around it and its diameter within skeleton_diameter_tolerance of theirs
// interpolated. Deviations are measured on the grids the file stores, so thinning a decoded
// tree again drops nothing more.
std::vector<bool> skeleton_nodes_to_keep(const LobeTree& tree, const TlobeOptions& o) {
    const TreeGraph& skeleton = tree.skeleton;
    std::vector<Eigen::Vector3f> position(skeleton.size());
    std::vector<float> diameter(skeleton.size());
    const double quantum = static_cast<float>(o.quantum), diameter_quantum = static_cast<float>(o.diameter_quantum);
    for (std::size_t i = 0; i < skeleton.size(); ++i) {
        for (int k = 0; k < 3; ++k)
            position[i][k] = static_cast<float>(static_cast<double>(quantize(skeleton.nodes[i].position[k], quantum)) * quantum);
        const std::int64_t d = quantize(2.0 * skeleton.nodes[i].radius, diameter_quantum);
        diameter[i] = static_cast<float>(static_cast<double>(d) * diameter_quantum);
    }
    std::vector<bool> keep(skeleton.size(), true), seed(skeleton.size(), false);
    for (const Lobe& lobe : tree.lobes)
        if (lobe.seed_node >= 0 && static_cast<std::size_t>(lobe.seed_node) < seed.size()) seed[lobe.seed_node] = true;
    const auto tolerance = static_cast<float>(o.skeleton_tolerance);
    const auto diameter_tolerance = std::max(static_cast<float>(o.skeleton_diameter_tolerance), 1e-9f);
    const auto thin = [&](std::span<const int> run) {
        const auto deviation = [&](std::size_t a, std::size_t b, std::size_t k) {  // > 1: keep
            const Eigen::Vector3f &pa = position[run[a]], &pb = position[run[b]], &pk = position[run[k]];
            const Eigen::Vector3f chord = pb - pa;
            const float t = chord.squaredNorm() > 0 ? std::clamp((pk - pa).dot(chord) / chord.squaredNorm(), 0.0f, 1.0f) : 0.0f;
            const float diameter_off = std::abs(diameter[run[k]] - ((1 - t) * diameter[run[a]] + t * diameter[run[b]]));
            return std::max(distance_to_segment(pk, pa, pb) / tolerance, diameter_off / diameter_tolerance);
        };
        const std::vector<char> kept = douglas_peucker(run.size(), 1.0f, deviation);
        for (std::size_t k = 0; k < run.size(); ++k) keep[run[k]] = keep[run[k]] && kept[k];
    };
    for (const std::vector<int>& chain : tree_chains(skeleton)) {
        std::size_t from = 0;  // runs between lobe seeds
        for (std::size_t k = 1; k < chain.size(); ++k)
            if (seed[chain[k]] || k + 1 == chain.size()) {
                thin(std::span<const int>(chain).subspan(from, k - from + 1));
                from = k;
            }
    }
    return keep;
}

// The tree as a file stores it: the main skeleton thinned (skeleton_nodes_to_keep). The
// reconstruction spaces nodes evenly along straight branches, so most are redundant: the second
// palm's 277 nodes become 69 at 3 cm and its skeleton 566 bytes 321 (docs/tlobe.md).
LobeTree with_thinned_skeleton(const LobeTree& tree, const TlobeOptions& o) {
    if (!(o.skeleton_tolerance > 0) || tree.skeleton.size() < 3) return tree;
    LobeTree thinned = tree;
    std::vector<int> new_index;
    thinned.skeleton = keep_nodes(tree.skeleton, skeleton_nodes_to_keep(tree, o), new_index);
    for (Lobe& lobe : thinned.lobes)
        if (lobe.seed_node >= 0 && static_cast<std::size_t>(lobe.seed_node) < new_index.size())
            lobe.seed_node = new_index[lobe.seed_node];
    return thinned;
}

// The tree without the main skeleton's bare twigs: chains from a fork to a tip, up to
// bare_twig_length long, that seed no lobe (TlobeOptions::bare_twig_length). Chains from the
// root are kept: they are the trunk. Nothing when the tree has no bare twig.
std::optional<LobeTree> without_bare_twigs(const LobeTree& tree, const TlobeOptions& o) {
    const TreeGraph& skeleton = tree.skeleton;
    std::vector<bool> keep(skeleton.size(), true), seed(skeleton.size(), false);
    for (const Lobe& lobe : tree.lobes)
        if (lobe.seed_node >= 0 && static_cast<std::size_t>(lobe.seed_node) < seed.size()) seed[lobe.seed_node] = true;
    bool any = false;
    for (const std::vector<int>& chain : tree_chains(skeleton)) {
        if (chain.size() < 2 || chain.front() == 0 || !skeleton.nodes[chain.back()].children.empty()) continue;
        double length = 0;
        bool seeds_a_lobe = false;
        for (std::size_t k = 1; k < chain.size(); ++k) {
            length += (skeleton.nodes[chain[k]].position - skeleton.nodes[chain[k - 1]].position).norm();
            seeds_a_lobe = seeds_a_lobe || seed[chain[k]];
        }
        if (seeds_a_lobe || length > o.bare_twig_length) continue;
        for (std::size_t k = 1; k < chain.size(); ++k) keep[chain[k]] = false;
        any = true;
    }
    if (!any) return std::nullopt;
    LobeTree pruned = tree;
    std::vector<int> new_index;
    pruned.skeleton = keep_nodes(skeleton, keep, new_index);
    for (Lobe& lobe : pruned.lobes)
        if (lobe.seed_node >= 0 && static_cast<std::size_t>(lobe.seed_node) < new_index.size()) lobe.seed_node = new_index[lobe.seed_node];
    return pruned;
}

// The last major version whose readers take a lobe mesh without faces as it is (6.0 derives it).
constexpr int kLastMajorWithStoredSurfacesOnly = 5;

// Lobes of `t` to have their surfaces derived (Lobe::surface_from_occupancy) whose occupancy, as
// a reader decodes it from `payload`, gives no closed alpha shape (a few configurations of cells
// do not: one lobe of 26 in 20 samples of terminalia forced to derive every surface) keep their
// stored surfaces. Returns whether any did.
bool keep_underivable_surfaces(LobeTree& t, const std::string& payload) {
    const LobeTree seen = decode_tlobe_payload(payload, "tlobe writer", kLastMajorWithStoredSurfacesOnly, kTlobeMinorVersion);
    bool kept = false;
    for (std::size_t i = 0; i < t.lobes.size(); ++i) {
        if (!t.lobes[i].surface_from_occupancy) continue;
        try {
            surface_of_occupancy(seen.lobes[i].occupancy, seen.alpha_factor, "tlobe writer");
        } catch (const Error&) {
            t.lobes[i].surface_from_occupancy = false;
            kept = true;
        }
    }
    return kept;
}

// A lobe's leaf share in one byte: 0..kLeafShareSteps for 0..1, kUnknownLeafShare when unknown.
constexpr std::uint8_t kLeafShareSteps = 254, kUnknownLeafShare = 255;

std::uint8_t encode_leaf_share(float share) {
    if (!(share >= 0)) return kUnknownLeafShare;
    return static_cast<std::uint8_t>(std::lround(std::min(share, 1.0f) * kLeafShareSteps));
}

float decode_leaf_share(std::uint8_t code) { return code == kUnknownLeafShare ? -1.0f : static_cast<float>(code) / kLeafShareSteps; }

void check_options(const TlobeOptions& o) {
    if (!(o.quantum > 0 && o.quantum <= 1) || !(o.diameter_quantum > 0 && o.diameter_quantum <= 1) ||
        !(o.lobe_quantum > 0 && o.lobe_quantum <= 1) || !(o.lobe_quantum_per_cell >= 0 && o.lobe_quantum_per_cell <= 1))
        throw Error::usage("tlobe: quanta must be in (0, 1] metres");
    if (o.compression_level < 1 || o.compression_level > 9) throw Error::usage("tlobe: compression level must be 1..9");
    for (double fraction : o.lobe_face_fractions)
        if (!(fraction > 0 && fraction < 1)) throw Error::usage("tlobe: lobe face fractions must be in (0, 1)");
    if (o.min_lobe_faces < 4) throw Error::usage("tlobe: lobes keep at least 4 faces");
    if (!(o.skeleton_tolerance >= 0 && o.skeleton_tolerance <= 1) ||
        !(o.skeleton_diameter_tolerance >= 0 && o.skeleton_diameter_tolerance <= 1))
        throw Error::usage("tlobe: skeleton tolerances must be in [0, 1] metres");
    if (!(o.bare_twig_length >= 0 && std::isfinite(o.bare_twig_length)))
        throw Error::usage("tlobe: the bare twig length must be >= 0 metres");
    if (!(o.min_points_per_cell >= 0 && std::isfinite(o.min_points_per_cell)))
        throw Error::usage("tlobe: the points per occupancy cell must be a number >= 0");
}

// The grid of the lobe vertices: lobe_quantum, or lobe_quantum_per_cell of the coarsest
// occupancy cell when that is coarser (the stored cells decide, so a decoded tree is encoded on
// the grid it came on).
double lobe_vertex_quantum(const TlobeOptions& o, const std::vector<const Occupancy*>& occupancy) {
    double cell = 0;
    for (const Occupancy* grid : occupancy) cell = std::max(cell, static_cast<double>(grid->cell));
    return static_cast<float>(std::max(o.lobe_quantum, o.lobe_quantum_per_cell * cell));
}

// The payload with lobe i's occupancy taken from `occupancy[i]`.
std::string encode_payload(const LobeTree& tree, const TlobeOptions& o, const std::vector<const Occupancy*>& occupancy) {
    ByteWriter w;
    for (int k = 0; k < 3; ++k) w.f64(tree.skeleton.origin[k]);
    w.f32(static_cast<float>(o.quantum));
    w.f32(static_cast<float>(o.diameter_quantum));
    const double lobe_quantum = lobe_vertex_quantum(o, occupancy);
    w.f32(static_cast<float>(lobe_quantum));  // since 5.0
    w.string(tree.species);
    for (double v : {tree.beta, tree.gamma, tree.fs, tree.alpha_factor, tree.root_diameter}) w.f32(static_cast<float>(v));
    // Decoding uses the stored (float) quanta, so encode with exactly those.
    const double quantum = static_cast<float>(o.quantum);
    TlobeOptions stored = o;
    stored.quantum = quantum;
    stored.diameter_quantum = static_cast<float>(o.diameter_quantum);
    encode_skeleton(tree.skeleton, stored, w);
    w.varint(tree.lobes.size());
    for (std::size_t i = 0; i < tree.lobes.size(); ++i) {
        const Lobe& lobe = tree.lobes[i];
        if (lobe.seed_node < 0 || static_cast<std::size_t>(lobe.seed_node) >= tree.skeleton.size())
            throw Error(ExitCode::Internal, "tlobe: lobe seed is not a skeleton node");
        w.varint(static_cast<std::uint64_t>(lobe.seed_node));
        w.varint(lobe.points);
        for (int k = 0; k < 3; ++k) w.svarint(std::lround(lobe.seed_direction[k] * 127.0f));
        if (lobe.mesh.origin != Eigen::Vector3d::Zero() && lobe.mesh.origin != tree.skeleton.origin)
            throw Error(ExitCode::Internal, "tlobe: lobe mesh is not in the tree's frame");
        if (lobe.surface_from_occupancy && occupancy[i]->empty())
            throw Error(ExitCode::Internal, "tlobe: a lobe surface to derive from no occupancy");
        encode_mesh(lobe.surface_from_occupancy ? TriangleMesh{} : lobe.mesh, lobe_quantum, w);  // 6.0: no faces = derived
        encode_occupancy_grid(*occupancy[i], quantum, w);
    }
    w.string(encode_occupancy_cells(occupancy));  // since 5.0: the cells of all lobes in one stream
    w.f32(static_cast<float>(tree.leaf_area_m2));                                  // since 3.1
    for (const Lobe& lobe : tree.lobes) w.u8(encode_leaf_share(lobe.leaf_share));  // since 3.2
    return w.bytes();
}

std::string pack(const std::string& raw, int level) {
    uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
    std::string file(kHeaderSize + packed_size, '\0');
    if (compress2(reinterpret_cast<Bytef*>(file.data() + kHeaderSize), &packed_size, reinterpret_cast<const Bytef*>(raw.data()),
                  static_cast<uLong>(raw.size()), level) != Z_OK)
        throw Error(ExitCode::Internal, "tlobe: deflate failed");
    file.resize(kHeaderSize + packed_size);
    std::memcpy(file.data(), kMagic.data(), 4);
    file[4] = static_cast<char>(kTlobeMajorVersion);
    file[5] = static_cast<char>(kTlobeMinorVersion);
    file[6] = file[7] = 0;  // flags, reserved
    put_u32(file, 8, static_cast<std::uint32_t>(raw.size()));
    put_u32(file, 12, static_cast<std::uint32_t>(packed_size));
    put_u32(file, 16, file_crc(file));
    return file;
}

// The occupancy of every lobe on a grid of `size` metres (rounded to the quantum); none when a
// lobe's grid, or the tree's, would hold more cells than a file may. Lobes without cluster
// points (a decoded tree) keep their occupancy.
std::optional<std::vector<Occupancy>> occupancy_on_grid(const LobeTree& tree, const TlobeOptions& o, double size) {
    const double quantum = static_cast<float>(o.quantum);
    const auto cell = static_cast<float>(static_cast<double>(std::max<long long>(1, std::llround(size / quantum))) * quantum);
    std::size_t tree_cells = 0;
    for (const Lobe& lobe : tree.lobes) {
        const std::size_t lobe_cells = occupancy_cell_count(lobe.cluster_points, cell);
        if (lobe_cells > kMaxOccupancyCells) return std::nullopt;
        tree_cells += lobe_cells;
    }
    if (tree_cells > kMaxOccupancyCellsPerTree) return std::nullopt;
    std::vector<Occupancy> grids(tree.lobes.size());
    for (std::size_t i = 0; i < tree.lobes.size(); ++i)
        grids[i] = tree.lobes[i].cluster_points.empty() ? tree.lobes[i].occupancy : occupancy_of(tree.lobes[i].cluster_points, cell);
    return grids;
}

// The lobes' cluster points per occupied cell of `grids` (their occupancy on one grid).
double points_per_occupied_cell(const LobeTree& tree, const std::vector<Occupancy>& grids) {
    std::size_t points = 0, cells = 0;
    for (std::size_t i = 0; i < tree.lobes.size(); ++i) {
        if (tree.lobes[i].cluster_points.empty()) continue;
        points += tree.lobes[i].cluster_points.size();
        cells += grids[i].occupied_count();
    }
    return cells == 0 ? 0.0 : static_cast<double>(points) / static_cast<double>(cells);
}

// The tree with every lobe surface simplified to `fraction` of its faces (at least min_faces) and
// inflated back to the extent of the surface it came from.
LobeTree with_coarser_lobes(const LobeTree& tree, double fraction, std::size_t min_faces) {
    LobeTree coarse = tree;
    for (Lobe& lobe : coarse.lobes) {
        SimplifyOptions simplify;
        simplify.tolerance = 0;  // the face count alone decides
        simplify.max_faces = std::max<std::size_t>(min_faces, std::llround(fraction * static_cast<double>(lobe.mesh.faces.size())));
        simplify.min_faces = min_faces;
        const TriangleMesh fine = lobe.mesh;
        if (simplify_closed_mesh(lobe.mesh, simplify)) inflate_to_contain(lobe.mesh, fine);  // false = kept as it is
    }
    return coarse;
}

}  // namespace

std::string encode_tlobe(const LobeTree& unthinned, const TlobeOptions& o) {
    check_options(o);
    const LobeTree tree = with_thinned_skeleton(unthinned, o);
    std::vector<const Occupancy*> stored(tree.lobes.size());
    bool from_points = false;
    for (std::size_t i = 0; i < tree.lobes.size(); ++i) {
        stored[i] = &tree.lobes[i].occupancy;
        from_points = from_points || !tree.lobes[i].cluster_points.empty();
    }
    if (!from_points) return pack(encode_payload(tree, o, stored), o.compression_level);
    // The occupancy draws the crown's outline and the lobe surfaces only bound it, so the finest
    // grid that fits wins, with the surfaces simplified (halving their faces) as far as it takes,
    // down to the fraction simplifications_per_grid; the further fractions only when no grid fits
    // with that (docs/rebuild.md, the palm at 2.9 and 3.8 kB).
    std::vector<LobeTree> simplified;  // the tree at each of lobe_face_fractions, made when first needed
    const auto surfaces = [&](std::size_t k) -> const LobeTree& {  // k = 0: as they are; k: the k-th fraction
        while (simplified.size() < k) simplified.push_back(with_coarser_lobes(tree, o.lobe_face_fractions[simplified.size()], o.min_lobe_faces));
        return k == 0 ? tree : simplified[k - 1];
    };
    std::optional<LobeTree> bare;  // the skeleton and lobe seeds without the bare twigs
    if (o.bare_twig_length > 0)
        if (auto pruned = without_bare_twigs(unthinned, o)) bare = with_thinned_skeleton(*pruned, o);
    const auto without_twigs = [&](std::size_t k) {  // surfaces(k) on the skeleton of `bare`
        LobeTree t = surfaces(k);
        t.skeleton = bare->skeleton;
        for (std::size_t i = 0; i < t.lobes.size(); ++i) t.lobes[i].seed_node = bare->lobes[i].seed_node;
        return t;
    };
    const std::size_t simplest = o.lobe_face_fractions.size(), per_grid = std::min(o.simplifications_per_grid, simplest);
    for (std::size_t deepest = per_grid; deepest <= simplest; ++deepest) {
        const std::size_t fullest = deepest == per_grid ? 0 : deepest;
        for (std::size_t c = 0; c < o.occupancy_cells.size(); ++c) {
            const auto grids = occupancy_on_grid(tree, o, o.occupancy_cells[c]);
            if (!grids || (c + 1 < o.occupancy_cells.size() && points_per_occupied_cell(tree, *grids) < o.min_points_per_cell)) continue;
            std::vector<const Occupancy*> use(grids->size());
            for (std::size_t i = 0; i < grids->size(); ++i) use[i] = &(*grids)[i];
            const auto file_of = [&](const LobeTree& t) { return pack(encode_payload(t, o, use), o.compression_level); };
            // One pass rules out a grid that does not fit at all: the smallest file on it, the
            // last resort there, has no surfaces stored where the occupancy can give them.
            LobeTree least = bare ? without_twigs(deepest) : surfaces(deepest);
            for (std::size_t i = 0, derived_cells = 0; i < least.lobes.size(); ++i) {
                const std::size_t cells = (*grids)[i].empty() ? 0 : (*grids)[i].occupied_count();
                least.lobes[i].surface_from_occupancy = o.surfaces_from_occupancy && cells > 0 && cells <= kMaxDerivedSurfaceCells &&
                                                        derived_cells + cells <= kMaxDerivedSurfaceCellsPerTree;
                if (least.lobes[i].surface_from_occupancy) derived_cells += cells;
            }
            std::string smallest = file_of(least);
            if (smallest.size() > o.max_bytes) continue;
            for (std::size_t k = fullest; k <= deepest; ++k)
                if (std::string file = file_of(surfaces(k)); file.size() <= o.max_bytes) return file;
            if (bare)
                if (std::string file = file_of(without_twigs(deepest)); file.size() <= o.max_bytes) return file;
            if (keep_underivable_surfaces(least, encode_payload(least, o, use))) {
                smallest = file_of(least);
                if (smallest.size() > o.max_bytes) continue;
            }
            return smallest;
        }
    }
    const Occupancy none;
    std::vector<const Occupancy*> use(tree.lobes.size(), &none);
    return pack(encode_payload(surfaces(simplest), o, use), o.compression_level);
}

LobeTree decode_tlobe(std::string_view file, const std::string& name) {
    if (file.size() < kHeaderSize || std::memcmp(file.data(), kMagic.data(), 4) != 0)
        throw Error::input(name, "not a .tlobe file (no TLOB header)");
    const int major = static_cast<unsigned char>(file[4]), minor = static_cast<unsigned char>(file[5]);
    if (major < kTlobeOldestMajorVersion || major > kTlobeMajorVersion)
        throw Error::input(name, ".tlobe version " + std::to_string(major) + "." + std::to_string(minor) +
                                         " is not supported (this build reads versions " + std::to_string(kTlobeOldestMajorVersion) +
                                         ".x to " + std::to_string(kTlobeMajorVersion) + ".x; run `treelobes lobes` on the scan again)");
    const std::uint32_t raw_size = get_u32(file, 8), packed_size = get_u32(file, 12);
    if (packed_size != file.size() - kHeaderSize) throw Error::input(name, "truncated .tlobe file (payload size mismatch)");
    if (get_u32(file, 16) != file_crc(file)) throw Error::input(name, "corrupt .tlobe file (CRC-32 mismatch)");
    if (raw_size > kMaxPayload || raw_size > kMaxInflateRatio * packed_size + 64)
        throw Error::input(name, "implausible .tlobe payload size (" + std::to_string(raw_size) + " bytes claimed from " +
                                         std::to_string(packed_size) + " compressed bytes)");
    std::string raw(raw_size, '\0');
    uLongf unpacked = raw_size;
    if (uncompress(reinterpret_cast<Bytef*>(raw.data()), &unpacked, reinterpret_cast<const Bytef*>(file.data() + kHeaderSize),
                   packed_size) != Z_OK ||
        unpacked != raw_size)
        throw Error::input(name, "corrupt .tlobe payload (inflate failed)");
    return decode_tlobe_payload(raw, name, major, minor);
}

namespace {

// Fields appended after the lobes: 3.1 added the leaf area, 3.2 the lobes' leaf shares; 4.0
// has both.
int appended_fields(int major, int minor) { return major == 3 ? minor : 2 + minor; }

}  // namespace

LobeTree decode_tlobe_payload(std::string_view raw, const std::string& name, int major, int minor) {
    ByteReader in(raw, name);
    LobeTree tree;
    Eigen::Vector3d origin;
    for (int k = 0; k < 3; ++k) origin[k] = in.f64();
    const double quantum = in.f32(), diameter_quantum = in.f32();
    const double lobe_quantum = major >= 5 ? in.f32() : quantum;
    if (!(quantum > 0 && quantum <= 1) || !(diameter_quantum > 0 && diameter_quantum <= 1) || !(lobe_quantum > 0 && lobe_quantum <= 1) ||
        !origin.allFinite())
        in.fail("invalid quantization or origin");
    tree.species = in.string();
    tree.beta = in.f32();
    tree.gamma = in.f32();
    tree.fs = in.f32();
    tree.alpha_factor = in.f32();
    tree.root_diameter = in.f32();
    tree.skeleton = decode_skeleton(in, quantum, diameter_quantum);
    tree.skeleton.origin = origin;
    const std::size_t lobes = in.count(6, "lobe count");
    tree.lobes.resize(lobes);
    for (Lobe& lobe : tree.lobes) {
        const std::uint64_t seed = in.varint();
        if (seed >= tree.skeleton.size()) in.fail("lobe seed is not a skeleton node");
        lobe.seed_node = static_cast<int>(seed);
        lobe.points = static_cast<std::size_t>(in.varint());
        Eigen::Vector3f d;
        for (int k = 0; k < 3; ++k) d[k] = static_cast<float>(in.svarint());
        lobe.seed_direction = d.norm() > 0 ? Eigen::Vector3f(d.normalized()) : Eigen::Vector3f::UnitZ();
        lobe.mesh = major == 3 ? decode_mesh_v3(in, lobe_quantum) : decode_mesh(in, lobe_quantum);
        lobe.occupancy = major >= 5 ? decode_occupancy_grid(in, quantum) : decode_occupancy_v4(in, quantum);
    }
    if (major >= 5) {
        std::vector<Occupancy> grids(tree.lobes.size());
        for (std::size_t i = 0; i < grids.size(); ++i) grids[i] = std::move(tree.lobes[i].occupancy);
        decode_occupancy_cells(in.take(in.count(1, "occupancy stream length")), grids, name);
        for (std::size_t i = 0; i < grids.size(); ++i) tree.lobes[i].occupancy = std::move(grids[i]);
    }
    if (major >= 6) {  // a lobe without faces has its surface from its occupancy
        std::size_t derived_cells = 0;
        for (Lobe& lobe : tree.lobes) {
            if (!lobe.mesh.faces.empty()) continue;
            derived_cells += lobe.occupancy.empty() ? 0 : lobe.occupancy.occupied_count();
            if (derived_cells > kMaxDerivedSurfaceCellsPerTree)
                in.fail("lobe surfaces to derive from more occupied cells than a file may hold");
            lobe.mesh = surface_of_occupancy(lobe.occupancy, tree.alpha_factor, name);
            lobe.surface_from_occupancy = true;
        }
    }
    const int fields = appended_fields(major, minor);
    if (fields >= 1) {
        tree.leaf_area_m2 = in.f32();
        if (!(tree.leaf_area_m2 >= 0 && tree.leaf_area_m2 < kMaxLeafArea)) in.fail("invalid leaf area");
    }
    if (fields >= 2)
        for (Lobe& lobe : tree.lobes) lobe.leaf_share = decode_leaf_share(in.u8());
    // A later minor version appends fields this build does not know: they are skipped.
    if (fields <= appended_fields(kTlobeMajorVersion, kTlobeMinorVersion) && !in.at_end()) in.fail("trailing bytes after the last field");
    return tree;
}

void write_tlobe(const LobeTree& tree, const std::filesystem::path& path, const TlobeOptions& options) {
    write_file_atomically(path, encode_tlobe(tree, options));
}

LobeTree read_tlobe(const std::filesystem::path& path) { return decode_tlobe(read_file(path), path.string()); }

}  // namespace treelobes::lobes
