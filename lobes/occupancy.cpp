#include "lobes/occupancy.hpp"

#include "core/error.hpp"
#include "core/range_coder.hpp"
#include "geometry/alpha_shape.hpp"
#include "lobes/mesh_coder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace treelobes::lobes {

namespace {

constexpr auto kMaxCells = static_cast<std::int64_t>(kMaxOccupancyCells);

std::array<std::int64_t, 3> index_of(const Eigen::Vector3f& p, float cell) {
    return {static_cast<std::int64_t>(std::floor(p.x() / cell)), static_cast<std::int64_t>(std::floor(p.y() / cell)),
            static_cast<std::int64_t>(std::floor(p.z() / cell))};
}

// First cell and size of the grid over `points`.
std::pair<std::array<std::int64_t, 3>, std::array<std::int64_t, 3>> grid_of(std::span<const Eigen::Vector3f> points, float cell) {
    std::array<std::int64_t, 3> lo{}, hi{};
    lo.fill(std::numeric_limits<std::int64_t>::max());
    hi.fill(std::numeric_limits<std::int64_t>::min());
    for (const auto& p : points) {
        const auto q = index_of(p, cell);
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], q[k]);
            hi[k] = std::max(hi[k], q[k]);
        }
    }
    return {lo, {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1}};
}

// Octree over a grid padded to a cube of 2^depth cells (depth >= 1): level d has node (x, y, z)
// covering cells [x, x+1) * 2^(depth-d) along x, ...; level depth is the grid itself. Only nodes
// that overlap the grid exist.
using Node = std::array<std::int64_t, 3>;

Node child_of(const Node& n, int c) { return {2 * n[0] + ((c >> 2) & 1), 2 * n[1] + ((c >> 1) & 1), 2 * n[2] + (c & 1)}; }

struct Pyramid {
    int depth = 1;
    std::vector<std::array<std::int64_t, 3>> size;  // nodes along x, y, z per level
    std::vector<std::vector<std::uint8_t>> bits;    // per level 0..depth, 1 = occupied; empty until filled

    // Sizes only (decoding fills `bits` as it goes).
    explicit Pyramid(const std::array<std::int64_t, 3>& grid_size) {
        while ((std::int64_t{1} << depth) < std::max({grid_size[0], grid_size[1], grid_size[2]})) ++depth;
        size.resize(depth + 1);
        for (int d = 0; d <= depth; ++d)
            for (int k = 0; k < 3; ++k) size[d][k] = ((grid_size[k] - 1) >> (depth - d)) + 1;
        bits.resize(depth + 1);
    }
    // Every level of `o`, from its cells up.
    explicit Pyramid(const Occupancy& o) : Pyramid(o.size) {
        bits[depth] = o.bits;
        for (int d = depth - 1; d >= 0; --d) {
            bits[d].assign(nodes(d), 0);
            for (std::int64_t x = 0; x < size[d + 1][0]; ++x)
                for (std::int64_t y = 0; y < size[d + 1][1]; ++y)
                    for (std::int64_t z = 0; z < size[d + 1][2]; ++z)
                        if (occupied(d + 1, {x, y, z})) bits[d][index(d, {x / 2, y / 2, z / 2})] = 1;
        }
    }
    std::size_t nodes(int d) const { return static_cast<std::size_t>(size[d][0] * size[d][1] * size[d][2]); }
    bool inside(int d, const Node& n) const {
        return n[0] >= 0 && n[1] >= 0 && n[2] >= 0 && n[0] < size[d][0] && n[1] < size[d][1] && n[2] < size[d][2];
    }
    std::size_t index(int d, const Node& n) const { return static_cast<std::size_t>((n[0] * size[d][1] + n[1]) * size[d][2] + n[2]); }
    bool occupied(int d, const Node& n) const { return bits[d][index(d, n)] != 0; }
};

// The adaptive models of the version 5 octree coding, shared by all lobes of a file. A child's
// bit is predicted by how far its level is from the cells (the top levels are nearly full, the
// last sparse), by how many of its parent's three neighbours on the child's side are occupied
// (crown shells are continuous surfaces: a child facing occupied neighbours is likely occupied
// too; the context of MPEG's geometry point cloud coding, ISO/IEC 23090-9) and by how many of its
// siblings before it were set.
struct OctreeModels {
    static constexpr int kLevelContexts = 3, kNeighbourContexts = 4, kSiblingContexts = 3;
    std::array<BitModel, kLevelContexts * kNeighbourContexts * kSiblingContexts> models{};

    BitModel& at(int levels_above_cells, int occupied_neighbours, int set_siblings) {
        const int level = std::min(levels_above_cells, kLevelContexts) - 1;
        return models[(level * kNeighbourContexts + occupied_neighbours) * kSiblingContexts + std::min(set_siblings, kSiblingContexts - 1)];
    }
};

// Occupied neighbours of parent `n` (level d) on the side of its child c, along x, y and z.
int occupied_neighbours(const Pyramid& p, int d, const Node& n, int c) {
    int count = 0;
    for (int axis = 0; axis < 3; ++axis) {
        Node neighbour = n;
        neighbour[axis] += ((c >> (2 - axis)) & 1) ? 1 : -1;
        count += p.inside(d, neighbour) && p.occupied(d, neighbour);
    }
    return count;
}

// Walks the octree of `p` breadth first, from the root; for every child inside the grid,
// `code(model, level, child)` gives its bit (the encoder codes the known bit, the decoder decodes
// one), except that an occupied node's last child is set without coding when none before it was.
// Set children are marked in `p.bits`.
template <class CodeBit>
void walk_octree(Pyramid& p, OctreeModels& models, CodeBit code) {
    p.bits[0].assign(1, 1);
    std::vector<Node> nodes{{0, 0, 0}};
    for (int level = 0; level < p.depth; ++level) {
        if (p.bits[level + 1].empty()) p.bits[level + 1].assign(p.nodes(level + 1), 0);
        std::vector<Node> next;
        for (const Node& n : nodes) {
            int last_inside = -1;
            for (int c = 0; c < 8; ++c)
                if (p.inside(level + 1, child_of(n, c))) last_inside = c;
            int set = 0;
            for (int c = 0; c <= last_inside; ++c) {
                const Node child = child_of(n, c);
                if (!p.inside(level + 1, child)) continue;
                const bool bit = (c == last_inside && set == 0) ||
                                 code(models.at(p.depth - level, occupied_neighbours(p, level, n, c), set), level + 1, child);
                if (!bit) continue;
                ++set;
                p.bits[level + 1][p.index(level + 1, child)] = 1;
                next.push_back(child);
            }
        }
        nodes = std::move(next);
    }
}

// A grid with an occupied cell: one without (only a damaged version 4 file gives one) is stored
// as no occupancy, since the octree codes an occupied root.
bool holds_cells(const Occupancy& o) { return !o.empty() && std::find(o.bits.begin(), o.bits.end(), 1) != o.bits.end(); }

}  // namespace

bool Occupancy::occupied(const Eigen::Vector3f& p) const {
    if (empty()) return false;
    const auto q = index_of(p, cell);
    std::size_t index = 0;
    for (int k = 0; k < 3; ++k) {
        const std::int64_t i = q[k] - first[k];
        if (i < 0 || i >= size[k]) return false;
        index = index * static_cast<std::size_t>(size[k]) + static_cast<std::size_t>(i);
    }
    return bits[index] != 0;
}

std::size_t Occupancy::occupied_count() const { return static_cast<std::size_t>(std::count(bits.begin(), bits.end(), 1)); }

Eigen::Vector3f Occupancy::cell_centre(std::size_t index) const {
    const auto k = static_cast<std::int64_t>(index % size[2]), j = static_cast<std::int64_t>((index / size[2]) % size[1]),
               i = static_cast<std::int64_t>(index / (size[2] * size[1]));
    return cell * Eigen::Vector3f(static_cast<float>(first[0] + i) + 0.5f, static_cast<float>(first[1] + j) + 0.5f,
                                  static_cast<float>(first[2] + k) + 0.5f);
}

std::size_t occupancy_cell_count(std::span<const Eigen::Vector3f> points, float cell) {
    if (points.empty()) return 0;
    const auto [first, size] = grid_of(points, cell);
    return static_cast<std::size_t>(size[0] * size[1] * size[2]);
}

Occupancy occupancy_of(std::span<const Eigen::Vector3f> points, float cell) {
    if (!(cell > 0)) throw Error::usage("occupancy: the cell size must be positive");
    Occupancy o;
    if (points.empty()) return o;
    o.cell = cell;
    std::tie(o.first, o.size) = grid_of(points, cell);
    if (o.size[0] * o.size[1] * o.size[2] > kMaxCells) throw Error::usage("occupancy: grid too fine for the points' extent");
    o.bits.assign(static_cast<std::size_t>(o.size[0] * o.size[1] * o.size[2]), 0);
    for (const auto& p : points) {
        const auto q = index_of(p, cell);
        o.bits[static_cast<std::size_t>(((q[0] - o.first[0]) * o.size[1] + (q[1] - o.first[1])) * o.size[2] + (q[2] - o.first[2]))] = 1;
    }
    return o;
}

void encode_occupancy_grid(const Occupancy& o, double quantum, ByteWriter& out) {
    if (!holds_cells(o)) {
        out.varint(0);
        return;
    }
    const auto steps = std::llround(o.cell / quantum);
    if (steps < 1 || static_cast<float>(static_cast<double>(steps) * quantum) != o.cell)
        throw Error(ExitCode::Internal, "occupancy: the cell size is not a multiple of the quantum");
    out.varint(static_cast<std::uint64_t>(steps));
    for (int k = 0; k < 3; ++k) out.svarint(o.first[k]);
    for (int k = 0; k < 3; ++k) out.varint(static_cast<std::uint64_t>(o.size[k]));
}

Occupancy decode_occupancy_grid(ByteReader& in, double quantum) {
    Occupancy o;
    const std::uint64_t steps = in.varint();
    if (steps == 0) return o;
    if (steps > (std::uint64_t{1} << 20)) in.fail("implausible occupancy cell size");
    o.cell = static_cast<float>(static_cast<double>(steps) * quantum);
    for (int k = 0; k < 3; ++k) o.first[k] = in.svarint();
    std::int64_t cells = 1;
    for (int k = 0; k < 3; ++k) {
        const std::uint64_t n = in.varint();
        if (n == 0 || n > static_cast<std::uint64_t>(kMaxCells)) in.fail("invalid occupancy grid size");
        o.size[k] = static_cast<std::int64_t>(n);
        cells *= o.size[k];
        if (cells > kMaxCells) in.fail("invalid occupancy grid size");
    }
    return o;
}

std::string encode_occupancy_cells(std::span<const Occupancy* const> grids) {
    RangeEncoder coder;
    OctreeModels models;
    bool any = false;
    for (const Occupancy* o : grids) {
        if (!holds_cells(*o)) continue;
        any = true;
        Pyramid pyramid(*o);
        walk_octree(pyramid, models, [&](BitModel& model, int level, const Node& child) {
            const bool bit = pyramid.occupied(level, child);
            coder.encode(model, bit);
            return bit;
        });
    }
    if (!any) return {};
    const std::vector<std::uint8_t> bytes = coder.finish();
    return {bytes.begin(), bytes.end()};
}

void decode_occupancy_cells(std::string_view stream, std::span<Occupancy> grids, const std::string& name) {
    std::size_t cells = 0;
    for (const Occupancy& o : grids)
        if (o.cell > 0) cells += static_cast<std::size_t>(o.size[0] * o.size[1] * o.size[2]);
    if (cells > kMaxOccupancyCellsPerTree) throw Error::input(name, "the lobes' occupancy grids hold more cells than a .tlobe may");
    if (cells == 0) {
        if (!stream.empty()) throw Error::input(name, "occupancy cells given for lobes without occupancy");
        return;
    }
    RangeDecoder decoder({reinterpret_cast<const std::uint8_t*>(stream.data()), stream.size()}, name);
    OctreeModels models;
    for (Occupancy& o : grids) {
        if (o.cell <= 0) continue;
        Pyramid pyramid(o.size);
        walk_octree(pyramid, models, [&](BitModel& model, int, const Node&) { return decoder.decode(model); });
        o.bits = std::move(pyramid.bits[pyramid.depth]);
    }
    if (!decoder.at_end()) throw Error::input(name, "trailing bytes after the occupancy cells");
}

Occupancy decode_occupancy_v4(ByteReader& in, double quantum) {
    Occupancy o = decode_occupancy_grid(in, quantum);
    if (o.cell <= 0) return o;
    const Pyramid pyramid(o.size);
    o.bits.assign(static_cast<std::size_t>(o.size[0] * o.size[1] * o.size[2]), 0);
    std::vector<Node> nodes{{0, 0, 0}};
    for (int level = 0; level < pyramid.depth; ++level) {
        std::vector<Node> next;
        for (const Node& n : nodes) {
            const std::uint8_t mask = in.u8();
            for (int c = 0; c < 8; ++c) {
                if (!((mask >> c) & 1)) continue;
                const Node child = child_of(n, c);
                if (!pyramid.inside(level + 1, child)) in.fail("occupancy octree node outside the grid");
                next.push_back(child);
            }
        }
        nodes = std::move(next);
    }
    for (const Node& n : nodes) o.bits[static_cast<std::size_t>((n[0] * o.size[1] + n[1]) * o.size[2] + n[2])] = 1;
    return o;
}

TriangleMesh surface_of_occupancy(const Occupancy& occupancy, double alpha_factor, const std::string& name) {
    if (occupancy.empty()) throw Error::input(name, "a lobe stores neither a surface nor an occupancy");
    if (!(alpha_factor >= 1 && alpha_factor <= 100)) throw Error::input(name, "alpha factor outside [1, 100]");
    const std::size_t cells = occupancy.occupied_count();
    if (cells == 0 || cells > kMaxDerivedSurfaceCells)
        throw Error::input(name, "a lobe surface to derive from " + std::to_string(cells) + " occupied cells (1 to " +
                                         std::to_string(kMaxDerivedSurfaceCells) + " may be)");
    // Corners as grid indices, so that the cells sharing one give it once.
    std::vector<std::array<std::int64_t, 3>> indices;
    indices.reserve(8 * cells);
    const std::array<std::int64_t, 3>& size = occupancy.size;
    for (std::size_t n = 0; n < occupancy.bits.size(); ++n) {
        if (!occupancy.bits[n]) continue;
        const auto cell = static_cast<std::int64_t>(n);
        const std::array<std::int64_t, 3> at{occupancy.first[0] + cell / (size[2] * size[1]),
                                             occupancy.first[1] + (cell / size[2]) % size[1], occupancy.first[2] + cell % size[2]};
        for (int k = 0; k < 8; ++k) indices.push_back({at[0] + (k & 1), at[1] + ((k >> 1) & 1), at[2] + ((k >> 2) & 1)});
    }
    std::sort(indices.begin(), indices.end());
    indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
    std::vector<Eigen::Vector3f> corners;
    corners.reserve(indices.size());
    for (const auto& index : indices)
        corners.push_back(occupancy.cell *
                          Eigen::Vector3f(static_cast<float>(index[0]), static_cast<float>(index[1]), static_cast<float>(index[2])));
    AlphaShapeOptions options;
    options.alpha_factor = alpha_factor;
    AlphaShapeResult shape = alpha_shape(corners, options);
    if (shape.mesh.faces.empty()) throw Error::input(name, "no lobe surface around its occupied cells: " + shape.failure);
    return std::move(shape.mesh);
}

}  // namespace treelobes::lobes
