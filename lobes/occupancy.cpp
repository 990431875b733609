#include "lobes/occupancy.hpp"

#include "core/error.hpp"
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
// covering cells [x, x+1) * 2^(depth-d) along x, ...; level depth is the grid itself.
using Node = std::array<std::int64_t, 3>;

Node child_of(const Node& n, int c) { return {2 * n[0] + ((c >> 2) & 1), 2 * n[1] + ((c >> 1) & 1), 2 * n[2] + (c & 1)}; }

struct Pyramid {
    int depth = 1;
    std::vector<std::array<std::int64_t, 3>> size;  // nodes along x, y, z per level
    std::vector<std::vector<std::uint8_t>> bits;    // per level; the leaf level is not copied

    explicit Pyramid(const Occupancy& o) : grid(&o) {
        while ((std::int64_t{1} << depth) < std::max({o.size[0], o.size[1], o.size[2]})) ++depth;
        size.resize(depth + 1);
        for (int d = 0; d <= depth; ++d)
            for (int k = 0; k < 3; ++k) size[d][k] = ((o.size[k] - 1) >> (depth - d)) + 1;
        bits.resize(depth);
        if (o.bits.empty()) return;  // decoding: sizes only
        for (int d = depth - 1; d >= 0; --d) {
            bits[d].assign(static_cast<std::size_t>(size[d][0] * size[d][1] * size[d][2]), 0);
            for (std::int64_t x = 0; x < size[d + 1][0]; ++x)
                for (std::int64_t y = 0; y < size[d + 1][1]; ++y)
                    for (std::int64_t z = 0; z < size[d + 1][2]; ++z)
                        if (occupied(d + 1, {x, y, z})) bits[d][index(d, {x / 2, y / 2, z / 2})] = 1;
        }
    }
    bool inside(int d, const Node& n) const { return n[0] < size[d][0] && n[1] < size[d][1] && n[2] < size[d][2]; }
    std::size_t index(int d, const Node& n) const { return static_cast<std::size_t>((n[0] * size[d][1] + n[1]) * size[d][2] + n[2]); }
    bool occupied(int d, const Node& n) const { return (d == depth ? grid->bits : bits[d])[index(d, n)] != 0; }

private:
    const Occupancy* grid;
};

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

void encode_occupancy(const Occupancy& o, double quantum, ByteWriter& out) {
    if (o.empty()) {
        out.varint(0);
        return;
    }
    const auto steps = std::llround(o.cell / quantum);
    if (steps < 1 || static_cast<float>(static_cast<double>(steps) * quantum) != o.cell)
        throw Error(ExitCode::Internal, "occupancy: the cell size is not a multiple of the quantum");
    out.varint(static_cast<std::uint64_t>(steps));
    for (int k = 0; k < 3; ++k) out.svarint(o.first[k]);
    for (int k = 0; k < 3; ++k) out.varint(static_cast<std::uint64_t>(o.size[k]));
    // Octree of child masks, breadth first: far fewer bytes than one bit per cell for the
    // crown-shell occupancies of large lobes, so finer cells fit the file budget.
    const Pyramid pyramid(o);
    std::vector<Node> nodes{{0, 0, 0}};
    for (int level = 0; level < pyramid.depth; ++level) {
        std::vector<Node> next;
        for (const Node& n : nodes) {
            std::uint8_t mask = 0;
            for (int c = 0; c < 8; ++c) {
                const Node child = child_of(n, c);
                if (pyramid.inside(level + 1, child) && pyramid.occupied(level + 1, child)) {
                    mask |= static_cast<std::uint8_t>(1u << c);
                    next.push_back(child);
                }
            }
            out.u8(mask);
        }
        nodes = std::move(next);
    }
}

Occupancy decode_occupancy(ByteReader& in, double quantum) {
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
    const Pyramid pyramid(o);  // no bits yet: only its level sizes
    o.bits.assign(static_cast<std::size_t>(cells), 0);
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

}  // namespace treelobes::lobes
