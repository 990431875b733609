// Weber & Penn style growth (see grow.hpp). Stems are processed breadth-first from a queue so
// node indices, random streams and therefore the output are fully determined by the seed.
#include "synth/grow.hpp"

#include "core/angles.hpp"
#include "core/error.hpp"
#include "core/random.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>

namespace treelobes::synth {

namespace {

using Vec3 = Eigen::Vector3d;

constexpr double kMinRadius = 0.0005;      // 1 mm twig tips: nothing real is thinner
constexpr std::size_t kMaxStems = 300000;  // a runaway profile fails instead of eating memory
constexpr std::size_t kMaxLeaves = 3000000;
constexpr double kGroundClearance = 0.3;  // weeping and spreading branches end on the ground, not in it

Vec3 rotate(const Vec3& v, const Vec3& axis, double degrees) {
    return Eigen::AngleAxisd(degrees * kRadiansPerDegree, axis.normalized()) * v;
}

Vec3 any_perpendicular(const Vec3& d) {
    const Vec3 helper = std::abs(d.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX();
    return d.cross(helper).normalized();
}

// `side` made perpendicular to `dir` again after `dir` turned.
Vec3 orthonormalise(const Vec3& side, const Vec3& dir) {
    const Vec3 s = side - side.dot(dir) * dir;
    return s.norm() < 1e-9 ? any_perpendicular(dir) : s.normalized();
}

Eigen::Vector3f to_float(const Vec3& v) { return v.cast<float>(); }

// One stem, or the part of a stem after a fork. Offsets are measured from the base of the
// full stem so that taper, child density and curvature continue across forks.
struct Stem {
    int level = 0;
    int parent_node = 0;  // the node the stem grows from
    Vec3 start{0, 0, 0};
    Vec3 dir{0, 0, 1};
    Vec3 side{1, 0, 0};               // bending axis: curve and down angle rotate about it
    double length = 0;                // planned length of the full stem
    double length_ratio = 1;          // length / maximum length at this level: scales children and leaves
    double radius = 0;                // radius at offset 0 of the full stem
    double radius_scale = 1;          // pipe-model reduction after forks
    int first_segment = 0;            // > 0 for the parts after a fork
    double child_begin = 0;           // offset where children start (trunk: the clear bole)
    std::uint64_t schedule_seed = 0;  // where the children and leaves sit along the stem
    bool main = true;                 // continues its parent node's stem (main child first)
    bool dead = false;                // in the dead lower crown (growth.dead_crown), with its descendants
};

// The chunk of a stem between its first segment and the next fork (or the tip).
struct Chunk {
    double seg_length = 0;
    double begin = 0, end = 0;  // offsets along the full stem
    std::vector<Vec3> points;   // segment end points, points[0] = start
    std::vector<Vec3> dirs;     // direction of each segment
    std::vector<Vec3> sides;
    Vec3 end_dir, end_side;  // direction after the last bend (for forks)

    std::size_t segment_at(double s) const {
        const double k = std::floor((s - begin) / seg_length);
        return static_cast<std::size_t>(std::clamp(k, 0.0, static_cast<double>(dirs.size() - 1)));
    }
    Vec3 position(double s) const {
        const std::size_t k = segment_at(s);
        return points[k] + dirs[k] * (s - begin - static_cast<double>(k) * seg_length);
    }
};

struct Placement {  // a child stem or leaf node along a stem
    double offset = 0;
    int index = 0;  // position in the schedule (phyllotaxis step)
    int count = 1;  // stems in this whorl / leaves in this cluster
};

// Leaf count and size multipliers (see grow(): the species' LAI within a leaf budget).
struct LeafScaling {
    double count = 1.0;
    double size = 1.0;
};

class Grower {
public:
    Grower(const SpeciesProfile& species, std::uint64_t seed, const GrowOptions& options, double height, double dbh, LeafScaling leaves)
            : growth_(species.growth),
              options_(options),
              seed_(seed),
              height_(height),
              dbh_(dbh),
              scaling_(leaves),
              split_error_(growth_.levels.size(), 0.0) {
        tree_.species = species.entry.name;
        tree_.species_id = species.entry.id;
        tree_.seed = seed;
        tree_.leaf_shape = growth_.leaves.shape;
        tree_.bark_reflectance = static_cast<float>(growth_.bark_reflectance);
        tree_.leaf_reflectance = static_cast<float>(growth_.leaf_reflectance);
    }

    SyntheticTree run() {
        plant_trunks();
        while (!queue_.empty()) {
            Stem stem = queue_.front();
            queue_.pop_front();
            grow_stem(stem);
        }
        order_main_children_first();
        return std::move(tree_);
    }

private:
    Rng stream(std::uint64_t key) { return Rng(stream_seed(seed_, key)); }

    void enqueue(const Stem& stem) {
        if (++stem_count_ > kMaxStems)
            throw Error::usage("species '" + tree_.species + "': growth makes more than " + std::to_string(kMaxStems) +
                               " stems; reduce growth.levels[].branches");
        queue_.push_back(stem);
    }

    // Trunk length, radius from the drawn DBH, lean, and base splits (multi-stemmed trees).
    void plant_trunks() {
        const StemLevel& trunk = growth_.levels[0];
        Rng rng = stream(0);
        const double base = std::clamp(growth_.base_size + rng.vary(growth_.base_size_v), 0.0, 0.98);
        const double length = height_ * std::clamp(trunk.length + rng.vary(trunk.length_v), 0.05, 1.0);
        const int stems = 1 + growth_.base_splits;
        const double scale = 1.0 / std::sqrt(static_cast<double>(stems));
        // Radius at offset 0 such that the (single-stem equivalent) diameter at 1.3 m is the DBH.
        const double z = std::min(1.3 / length, 0.99);
        const double radius = 0.5 * dbh_ / (std::max(taper_factor(trunk, z), 0.05) * flare(z));

        const Vec3 lean_axis = rotate(Vec3::UnitX(), Vec3::UnitZ(), rng.uniform(0, 360));
        const Vec3 up = rotate(Vec3::UnitZ(), lean_axis, rng.uniform(0, growth_.lean_v));
        add_node(Vec3::Zero(), radius * flare(0.0), -1, 0, radius * flare(0.0), true);

        const double phase = rng.uniform(0, 360);
        for (int i = 0; i < stems; ++i) {
            Stem stem;
            stem.level = 0;
            stem.parent_node = 0;
            stem.length = stems == 1 ? length : length * (1.0 + rng.vary(0.15));
            stem.radius = radius;
            stem.radius_scale = scale;
            stem.child_begin = base * stem.length;
            stem.schedule_seed = stream_seed(seed_, 1000 + i);
            stem.main = i == 0;
            if (stems == 1) {
                stem.dir = up;
                stem.side = any_perpendicular(up);
            } else {
                const Vec3 axis = rotate(any_perpendicular(up), up, phase + 360.0 * i / stems);
                stem.dir = rotate(up, axis, trunk.split_angle + rng.vary(trunk.split_angle_v));
                stem.side = axis;
            }
            enqueue(stem);
        }
    }

    // Weber & Penn root-collar flare over the lowest eighth of the trunk (z = offset / length).
    double flare(double z) const {
        const double y = std::max(0.0, 1.0 - 8.0 * z);
        return 1.0 + growth_.flare * (std::pow(100.0, y) - 1.0) / 100.0;
    }

    // Radius along a stem relative to its base (z = offset / length): taper to the tip, cone
    // (taper_power 1) or the fuller paraboloid of real boles (0.5).
    static double taper_factor(const StemLevel& level, double z) {
        return std::pow(std::max(1.0 - level.taper * z, 0.0), level.taper_power);
    }

    double stem_radius(const Stem& stem, double offset) const {
        const StemLevel& level = growth_.levels[stem.level];
        const double z = offset / stem.length;
        double r = stem.radius * stem.radius_scale * taper_factor(level, z);
        if (stem.level == 0) r *= flare(z);
        return std::max(r, kMinRadius);
    }

    // Bends the direction after segment k: curve (and curve_back for S-shapes), random
    // curvature about a random axis, and tropism toward (or away from) the sky.
    void bend(const StemLevel& level, int k, Vec3& dir, Vec3& side, Rng& rng) const {
        const int n = level.segments;
        double angle = level.curve / n;
        if (level.curve_back != 0) {
            const double half = std::max(1, n / 2);
            angle = (k < n / 2 ? level.curve : level.curve_back) / half;
        }
        dir = rotate(dir, side, angle);
        if (level.curve_v != 0) {
            const Vec3 axis = rotate(side, dir, rng.uniform(0, 360));
            dir = rotate(dir, axis, rng.vary(level.curve_v) / n);
        }
        if (level.tropism != 0) {
            const Vec3 pulled = dir + (level.tropism / n) * Vec3::UnitZ();
            if (pulled.norm() > 1e-6) dir = pulled.normalized();
        }
        side = orthonormalise(side, dir);
    }

    // A branch about to dip below the clearance height turns horizontal: it creeps over the
    // ground like the lowest limbs of willows and figs instead of growing into it.
    static void run_along_ground(Vec3& dir, Vec3& side) {
        Vec3 flat(dir.x(), dir.y(), 0.0);
        if (flat.norm() < 1e-6) flat = Vec3(side.x(), side.y(), 0.0);
        if (flat.norm() < 1e-6) flat = Vec3::UnitX();
        dir = flat.normalized();
        side = orthonormalise(side, dir);
    }

    // Forks of Weber & Penn's SegSplits with their per-level error diffusion.
    int forks_after(const Stem& stem, const StemLevel& level, double offset) {
        if (level.seg_splits <= 0) return 0;
        if (stem.level == 0 && offset < stem.child_begin) return 0;  // the bole stays single
        const double effective = level.seg_splits + split_error_[stem.level];
        const int clones = static_cast<int>(std::floor(effective + 0.5));
        split_error_[stem.level] = effective - clones;
        return std::max(clones, 0);
    }

    Chunk trace(const Stem& stem, Rng& rng, int& forks) {
        const StemLevel& level = growth_.levels[stem.level];
        Chunk chunk;
        chunk.seg_length = stem.length / level.segments;
        chunk.begin = stem.first_segment * chunk.seg_length;
        chunk.points.push_back(stem.start);
        Vec3 dir = stem.dir, side = stem.side;
        forks = 0;
        int k = stem.first_segment;
        for (; k < level.segments; ++k) {
            if (stem.level > 0 && dir.z() < 0 && chunk.points.back().z() + dir.z() * chunk.seg_length < kGroundClearance)
                run_along_ground(dir, side);
            chunk.dirs.push_back(dir);
            chunk.sides.push_back(side);
            chunk.points.push_back(chunk.points.back() + dir * chunk.seg_length);
            bend(level, k, dir, side, rng);
            if (k + 1 < level.segments && (forks = forks_after(stem, level, (k + 1) * chunk.seg_length)) > 0) {
                ++k;
                break;
            }
        }
        chunk.end = k * chunk.seg_length;
        chunk.end_dir = dir;
        chunk.end_side = side;
        return chunk;
    }

    // Evenly spread nodes with jitter between `begin` and `length`; `per_node` items each.
    static std::vector<Placement> schedule(std::uint64_t seed, double expected, int per_node, double begin, double length) {
        Rng rng(seed);
        const int total = rng.stochastic_round(std::max(expected, 0.0));
        std::vector<Placement> nodes;
        if (total <= 0 || begin >= length) return nodes;
        const int count = (total + per_node - 1) / per_node;
        for (int j = 0; j < count; ++j) {
            Placement p;
            p.offset = begin + (length - begin) * (j + 0.5 + rng.vary(0.3)) / count;
            p.index = j;
            p.count = std::min(per_node, total - j * per_node);
            nodes.push_back(p);
        }
        return nodes;
    }

    // Azimuth of item m of placement j: spiral phyllotaxis, or alternate left/right sprays.
    static double azimuth(const StemLevel& level, double phase, const Placement& p, int m, Rng& rng) {
        const double spread = 360.0 * m / p.count;
        if (level.rotate < 0) return 90.0 + 180.0 * (p.index % 2) + spread + rng.vary(level.rotate_v);
        return phase + p.index * level.rotate + spread + rng.vary(level.rotate_v);
    }

    int add_node(const Vec3& position, double radius, int parent, int level, double start_radius, bool main) {
        const int node = tree_.skeleton.add_node(to_float(position), static_cast<float>(radius), parent);
        tree_.node_level.push_back(level);
        tree_.internode_start_radius.push_back(static_cast<float>(start_radius));
        main_.push_back(main ? 1 : 0);
        return node;
    }

    // Node offsets of a chunk: segment ends, child positions (snapped to a segment end when
    // very close, so whorls share a node) and subdivisions of long internodes.
    std::vector<double> node_offsets(const Chunk& chunk, std::vector<Placement>& children) const {
        std::vector<double> offsets;
        for (double s = chunk.begin + chunk.seg_length; s < chunk.end + 0.5 * chunk.seg_length; s += chunk.seg_length)
            offsets.push_back(std::min(s, chunk.end));
        const double snap = std::min(0.02, 0.1 * chunk.seg_length);
        for (auto& c : children) {
            auto nearest = std::min_element(offsets.begin(), offsets.end(),
                                            [&](double a, double b) { return std::abs(a - c.offset) < std::abs(b - c.offset); });
            if (std::abs(*nearest - c.offset) < snap)
                c.offset = *nearest;
            else
                offsets.push_back(c.offset);
        }
        std::sort(offsets.begin(), offsets.end());
        std::vector<double> refined;
        double previous = chunk.begin;
        for (double s : offsets) {
            const int pieces = static_cast<int>(std::ceil((s - previous) / options_.max_internode_m - 1e-9));
            for (int i = 1; i < pieces; ++i) refined.push_back(previous + (s - previous) * i / pieces);
            refined.push_back(s);
            previous = s;
        }
        return refined;
    }

    void grow_stem(const Stem& stem) {
        Rng rng = stream(2000000 + stem_index_++);
        int forks = 0;
        const Chunk chunk = trace(stem, rng, forks);
        const int level_count = static_cast<int>(growth_.levels.size());
        const bool last_level = stem.level + 1 == level_count;
        const bool leafy = options_.leaves && !stem.dead && stem.level >= std::max(1, level_count - growth_.leaves.levels);

        std::vector<Placement> children;
        if (!last_level) children = child_schedule(stem, chunk);
        const std::vector<double> offsets = node_offsets(chunk, children);

        // Nodes along the chunk; the first internode starts at the parent node.
        std::vector<int> nodes;
        int previous = stem.parent_node;
        double previous_radius = stem_radius(stem, chunk.begin);
        for (double s : offsets) {
            const double r = stem_radius(stem, s);
            previous = add_node(chunk.position(s), r, previous, stem.level, previous_radius, nodes.empty() ? stem.main : true);
            nodes.push_back(previous);
            previous_radius = r;
        }
        auto node_at = [&](double s) {
            const auto it = std::lower_bound(offsets.begin(), offsets.end(), s - 1e-9);
            return nodes[std::min<std::size_t>(it - offsets.begin(), nodes.size() - 1)];
        };

        if (!last_level) spawn_children(stem, chunk, children, node_at, rng);
        if (leafy) {
            // Own stream: the leaf count changes between the two growth passes of grow(), the
            // branching decisions below must not.
            Rng leaf_rng = stream(900000000ULL + stem_index_);
            add_leaves(stem, chunk, node_at, leaf_rng);
        }
        if (forks > 0) spawn_forks(stem, chunk, forks, nodes.back(), rng);
    }

    std::vector<Placement> child_schedule(const Stem& stem, const Chunk& chunk) const {
        const StemLevel& child = growth_.levels[stem.level + 1];
        double expected = stem.level == 0 ? child.branches : child.branches * (0.2 + 0.8 * stem.length_ratio);
        if (stem.dead) expected *= 0.5;  // dead branches have shed half their side shoots
        const double begin = stem.child_begin;
        std::vector<Placement> all = schedule(stem.schedule_seed, expected, child.whorl, begin, stem.length);
        std::vector<Placement> mine;
        for (const auto& p : all)
            if (p.offset >= chunk.begin && (p.offset < chunk.end || chunk.end >= stem.length - 1e-9)) mine.push_back(p);
        return mine;
    }

    template <typename NodeAt>
    void spawn_children(const Stem& stem, const Chunk& chunk, const std::vector<Placement>& placements, NodeAt node_at, Rng& rng) {
        const StemLevel& level = growth_.levels[stem.level + 1];
        const double phase = rng.uniform(0, 360);
        for (const Placement& p : placements) {
            const std::size_t k = chunk.segment_at(p.offset);
            const Vec3 dir = chunk.dirs[k], side = chunk.sides[k];
            const Vec3 across = dir.cross(side);
            const int node = node_at(p.offset);
            const Vec3 start = tree_.skeleton.nodes[node].position.cast<double>();
            for (int m = 0; m < p.count; ++m) {
                const double phi = azimuth(level, phase, p, m, rng) * kRadiansPerDegree;
                const Vec3 axis = std::cos(phi) * side + std::sin(phi) * across;
                Stem child;
                child.level = stem.level + 1;
                child.parent_node = node;
                child.start = start;
                child.dir = rotate(dir, axis, down_angle(stem, level, p.offset, rng));
                child.side = orthonormalise(axis, child.dir);
                set_child_length(stem, level, p.offset, rng, child);
                const double fit = std::pow(child.length / stem.length, growth_.ratio_power);
                const double widest = std::max(kMinRadius, 0.9 * stem_radius(stem, p.offset));
                child.radius = std::clamp(stem.radius * stem.radius_scale * fit, kMinRadius, widest);
                const bool has_children = child.level + 1 < static_cast<int>(growth_.levels.size());
                child.child_begin = has_children ? growth_.levels[child.level + 1].start * child.length : 0.0;
                child.schedule_seed = rng.next();
                child.main = false;
                // Dead lower crown: first-order branches low on the trunk, and everything on them.
                child.dead = stem.dead || (stem.level == 0 && crown_position(stem, p.offset) > 1.0 - growth_.dead_crown);
                enqueue(child);
            }
        }
    }

    // Weber & Penn: a negative down_angle_v on the first level makes low branches droop and
    // high ones rise, following a conical profile along the crown.
    double down_angle(const Stem& parent, const StemLevel& level, double offset, Rng& rng) const {
        if (level.down_angle_v >= 0 || parent.level != 0) return level.down_angle + rng.vary(std::abs(level.down_angle_v));
        const double r = crown_position(parent, offset);
        return level.down_angle + level.down_angle_v * (1.0 - 2.0 * crown_shape_ratio(CrownShape::Conical, r)) +
               rng.vary(0.1 * std::abs(level.down_angle_v));
    }

    // 1 at the crown base, 0 at the top of the trunk.
    static double crown_position(const Stem& trunk, double offset) {
        const double span = std::max(trunk.length - trunk.child_begin, 1e-6);
        return std::clamp((trunk.length - offset) / span, 0.0, 1.0);
    }

    void set_child_length(const Stem& parent, const StemLevel& level, double offset, Rng& rng, Stem& child) const {
        const double factor = std::max(level.length + rng.vary(level.length_v), 0.01);
        const double maximum = level.length + level.length_v;
        if (parent.level == 0) {
            const double shape = crown_shape_ratio(growth_.shape, crown_position(parent, offset));
            child.length = parent.length * factor * std::max(shape, 0.05);
            child.length_ratio = child.length / (parent.length * maximum);
        } else {
            child.length = factor * (parent.length - 0.6 * offset);
            child.length_ratio = child.length / (maximum * parent.length);
        }
        child.length = std::max(child.length, 0.02);
        child.length_ratio = std::clamp(child.length_ratio, 0.0, 1.0);
    }

    void spawn_forks(const Stem& stem, const Chunk& chunk, int forks, int fork_node, Rng& rng) {
        const StemLevel& level = growth_.levels[stem.level];
        const int stems = forks + 1;
        const Vec3 axis0 = rotate(chunk.end_side, chunk.end_dir, rng.uniform(0, 360));
        for (int i = 0; i < stems; ++i) {
            const Vec3 axis = rotate(axis0, chunk.end_dir, 360.0 * i / stems);
            Stem part = stem;
            part.parent_node = fork_node;
            part.start = tree_.skeleton.nodes[fork_node].position.cast<double>();
            part.dir = rotate(chunk.end_dir, axis, 0.5 * (level.split_angle + rng.vary(level.split_angle_v)));
            part.side = orthonormalise(axis, part.dir);
            part.radius_scale = stem.radius_scale / std::sqrt(static_cast<double>(stems));
            part.first_segment = static_cast<int>(std::lround(chunk.end / chunk.seg_length));
            part.main = i == 0;
            if (i > 0) part.schedule_seed = rng.next();
            enqueue(part);
        }
    }

    template <typename NodeAt>
    void add_leaves(const Stem& stem, const Chunk& chunk, NodeAt node_at, Rng& rng) {
        const LeafProfile& lp = growth_.leaves;
        const StemLevel& level = growth_.levels[stem.level];
        const double expected = lp.per_branch * scaling_.count * (0.2 + 0.8 * stem.length_ratio) * lp.cluster;
        // Leaflets sit in opposite pairs left and right of the rachis; other leaves spiral.
        StemLevel arrangement = level;
        arrangement.rotate = lp.shape == LeafShape::Leaflet ? -90.0 : 137.5;
        arrangement.rotate_v = 10;
        const double phase = rng.uniform(0, 360);
        for (const Placement& p : schedule(stem.schedule_seed ^ 0x5bd1e995ULL, expected, lp.cluster, lp.start * stem.length, stem.length)) {
            if (p.offset < chunk.begin || p.offset > chunk.end) continue;
            const std::size_t k = chunk.segment_at(p.offset);
            const Vec3 dir = chunk.dirs[k], side = chunk.sides[k], across = dir.cross(side);
            const Vec3 at = chunk.position(p.offset);
            const int node = node_at(p.offset);
            for (int m = 0; m < p.count; ++m) {
                const double phi = azimuth(arrangement, phase, p, m, rng) * kRadiansPerDegree;
                const Vec3 axis = std::cos(phi) * side + std::sin(phi) * across;
                const Vec3 d = rotate(dir, axis, lp.down_angle + rng.vary(lp.down_angle_v)).normalized();
                add_leaf(at + d * stem_radius(stem, p.offset), dir, d, node, rng);
            }
        }
    }

    // A blade lies in the plane of twig and leaf direction, then turns to face the sky by face_up.
    void add_leaf(const Vec3& base, const Vec3& twig, const Vec3& d, int node, Rng& rng) {
        const LeafProfile& lp = growth_.leaves;
        Vec3 n = twig.cross(d);
        n = n.norm() < 1e-6 ? any_perpendicular(d) : n.normalized();
        if (n.z() < 0) n = -n;
        const Vec3 faced = (1.0 - lp.face_up) * n + lp.face_up * Vec3::UnitZ();
        const Vec3 in_plane = faced - faced.dot(d) * d;
        if (in_plane.norm() > 1e-6) n = in_plane.normalized();
        const double size = (1.0 + rng.vary(lp.size_v)) * scaling_.size;
        if (tree_.leaves.size() >= kMaxLeaves)
            throw Error::usage("species '" + tree_.species + "': more than " + std::to_string(kMaxLeaves) +
                               " leaves; reduce growth.leaves.per_branch");
        Leaf leaf;
        leaf.base = to_float(base);
        leaf.direction = to_float(d);
        leaf.normal = to_float(n);
        leaf.length = static_cast<float>(lp.length_m * size);
        leaf.width = static_cast<float>(lp.width_m * size);
        leaf.internode = node;
        tree_.leaves.push_back(leaf);
    }

    // Main child first: the continuation of a stem before laterals and fork clones.
    void order_main_children_first() {
        for (auto& node : tree_.skeleton.nodes)
            std::stable_sort(node.children.begin(), node.children.end(), [&](int a, int b) { return main_[a] > main_[b]; });
    }

    const GrowthProfile& growth_;
    GrowOptions options_;
    std::uint64_t seed_;
    double height_, dbh_;
    LeafScaling scaling_;
    std::vector<double> split_error_;
    std::deque<Stem> queue_;
    std::size_t stem_count_ = 0;
    std::uint64_t stem_index_ = 0;
    std::vector<char> main_;
    SyntheticTree tree_;
};

// Height, age and DBH of one individual: the height uniform in its range, age and DBH
// correlated with it (quantile + noise) so that big trees are usually old and thick.
struct Individual {
    double height, age, dbh;
};

Individual draw_individual(const VariationProfile& v, std::uint64_t seed, double forced_height) {
    Rng rng(stream_seed(seed, 0xA11CE));
    const auto lerp = [](const ValueRange& r, double t) { return r.min + (r.max - r.min) * std::clamp(t, 0.0, 1.0); };
    double u = rng.uniform();
    if (forced_height > 0 && v.height_m.max > v.height_m.min) u = (forced_height - v.height_m.min) / (v.height_m.max - v.height_m.min);
    const double age_t = u + 0.15 * rng.normal();
    const double dbh_t = 0.7 * u + 0.3 * std::clamp(age_t, 0.0, 1.0) + 0.1 * rng.normal();
    return {forced_height > 0 ? forced_height : lerp(v.height_m, u), lerp(v.age_years, age_t), lerp(v.dbh_m, dbh_t)};
}

// Leaf multipliers: `lai` x crown projection is the wanted leaf area; leaf_density and the
// budget trade numbers of leaves against their size, keeping that area.
// `scale`: how much larger the final tree is than `nominal` (its crown projection grows with
// scale^2, the nominal leaf area does not: same twigs, same leaves).
LeafScaling leaf_scaling(const SpeciesProfile& species, const SyntheticTree& nominal, double scale, const GrowOptions& options) {
    const TreeMetrics m = measure(nominal);
    const double lai = species.growth.leaves.lai;
    const double area = lai > 0 && m.leaf_area_m2 > 0 ? lai / m.lai * scale * scale : 1.0;  // wanted / nominal area
    LeafScaling s;
    s.count = area * options.leaf_density;
    const double leaves = static_cast<double>(std::max<std::size_t>(m.leaves, 1));
    if (leaves * s.count > static_cast<double>(options.max_leaves)) s.count = static_cast<double>(options.max_leaves) / leaves;
    s.size = std::sqrt(area / s.count);
    return s;
}

double top_of(const SyntheticTree& tree) {
    double top = 0;
    for (const auto& node : tree.skeleton.nodes) top = std::max(top, static_cast<double>(node.position.z()));
    for (const auto& leaf : tree.leaves)
        for (const auto& c : leaf_corners(leaf, tree.leaf_shape)) top = std::max(top, static_cast<double>(c.z()));
    return top;
}

}  // namespace

SyntheticTree grow(const SpeciesProfile& species, std::uint64_t seed, const GrowOptions& options) {
    if (options.height_m < 0 || options.height_m > 150)
        throw Error::usage("tree height " + std::to_string(options.height_m) + " m is outside [0, 150] (0 = from the species)");
    if (!(options.leaf_density >= 0.001 && options.leaf_density <= 4))
        throw Error::usage("leaf density " + std::to_string(options.leaf_density) + " is outside [0.001, 4]");
    if (options.max_leaves < 1 || options.max_leaves > 20'000'000) throw Error::usage("leaf budget must be in [1, 20000000]");
    if (!(options.max_internode_m >= 0.05)) throw Error::usage("max internode length must be at least 0.05 m");
    const Individual who = draw_individual(species.variation, seed, options.height_m);
    // A first growth with the profile's nominal leaves measures the tree. Crowns rise above the
    // trunk or end below it depending on the species, so the second growth (same random
    // streams) is scaled by target/top to land on the drawn height, and gets as many leaves as
    // the species' leaf area index asks for, within the leaf budget.
    SyntheticTree first = Grower(species, seed, options, who.height, who.dbh, {}).run();
    const double top = top_of(first);
    const double nominal = top > 0.1 ? who.height * who.height / top : who.height;
    SyntheticTree tree =
            Grower(species, seed, options, nominal, who.dbh, leaf_scaling(species, first, nominal / who.height, options)).run();
    tree.age_years = who.age;
    return tree;
}

std::array<Eigen::Vector3f, 4> leaf_corners(const Leaf& leaf, LeafShape shape) {
    const Eigen::Vector3f d = leaf.direction;
    const Eigen::Vector3f s = d.cross(leaf.normal).normalized() * (0.5f * leaf.width);
    const Eigen::Vector3f tip = leaf.base + d * leaf.length;
    if (shape == LeafShape::Needle) return {leaf.base + s, tip + s, tip - s, leaf.base - s};
    const Eigen::Vector3f widest = leaf.base + d * (0.4f * leaf.length);
    return {leaf.base, widest + s, tip, widest - s};
}

TreeMetrics measure(const SyntheticTree& tree) {
    TreeMetrics m;
    const auto& nodes = tree.skeleton.nodes;
    m.internodes = nodes.empty() ? 0 : nodes.size() - 1;
    m.leaves = tree.leaves.size();
    m.total_length_m = tree.skeleton.total_length();
    m.height_m = top_of(tree);

    // Stems crossing 1.3 m: trunk internodes (level 0) whose ends straddle the height.
    double sum_d2 = 0;
    for (std::size_t i = 1; i < nodes.size(); ++i) {
        if (tree.node_level[i] != 0) continue;
        const auto& a = nodes[nodes[i].parent].position;
        const auto& b = nodes[i].position;
        if ((a.z() - 1.3f) * (b.z() - 1.3f) > 0 || a.z() == b.z()) continue;
        if (b.z() == 1.3f && a.z() < 1.3f) continue;  // counted once, by the internode above
        const double t = (1.3 - a.z()) / (b.z() - a.z());
        const double r = tree.internode_start_radius[i] + t * (nodes[i].radius - tree.internode_start_radius[i]);
        sum_d2 += 4 * r * r;
    }
    m.dbh_m = std::sqrt(sum_d2);

    Eigen::Vector2d lo(0, 0), hi(0, 0);
    const auto extend = [&](const Eigen::Vector3f& p) {
        lo = lo.cwiseMin(p.head<2>().cast<double>());
        hi = hi.cwiseMax(p.head<2>().cast<double>());
    };
    for (const auto& node : nodes) extend(node.position);
    for (const auto& leaf : tree.leaves)
        for (const auto& c : leaf_corners(leaf, tree.leaf_shape)) extend(c);
    m.crown_diameter_m = 0.5 * ((hi.x() - lo.x()) + (hi.y() - lo.y()));
    // Rhombi cover half their bounding rectangle, needles (strips) all of it.
    const double coverage = tree.leaf_shape == LeafShape::Needle ? 1.0 : 0.5;
    for (const auto& leaf : tree.leaves) m.leaf_area_m2 += coverage * leaf.length * leaf.width;
    const double projection = 0.25 * 3.14159265358979323846 * m.crown_diameter_m * m.crown_diameter_m;
    m.lai = projection > 0 ? m.leaf_area_m2 / projection : 0.0;
    return m;
}

void prune_subtrees(SyntheticTree& tree, const std::function<bool(int node)>& remove) {
    const std::vector<TreeNode>& old = tree.skeleton.nodes;
    // A node's parent has a smaller index (TreeGraph::add_node), so one pass in index order sees
    // every parent's fate before its children's.
    std::vector<int> new_index(old.size(), -1);
    int kept = 0;
    for (std::size_t i = 0; i < old.size(); ++i) {
        const int parent = old[i].parent;
        if (i != 0 && (parent < 0 || parent >= static_cast<int>(i)))
            throw Error(ExitCode::Internal, "prune_subtrees: node " + std::to_string(i) + " does not follow its parent");
        const bool gone = i != 0 && (new_index[static_cast<std::size_t>(parent)] < 0 || remove(static_cast<int>(i)));
        if (!gone) new_index[i] = kept++;
    }
    if (kept == static_cast<int>(old.size())) return;

    TreeGraph pruned;
    pruned.origin = tree.skeleton.origin;
    std::vector<int> level;
    std::vector<float> start_radius;
    for (std::size_t i = 0; i < old.size(); ++i) {
        if (new_index[i] < 0) continue;
        const int parent = old[i].parent < 0 ? -1 : new_index[static_cast<std::size_t>(old[i].parent)];
        pruned.add_node(old[i].position, old[i].radius, parent);
        level.push_back(tree.node_level[i]);
        start_radius.push_back(tree.internode_start_radius[i]);
    }
    // add_node lists children in index order; restore the original order (main child first).
    for (std::size_t i = 0; i < old.size(); ++i) {
        if (new_index[i] < 0) continue;
        std::vector<int> children;
        for (const int child : old[i].children)
            if (new_index[static_cast<std::size_t>(child)] >= 0) children.push_back(new_index[static_cast<std::size_t>(child)]);
        pruned.nodes[static_cast<std::size_t>(new_index[i])].children = children;
    }
    std::vector<Leaf> leaves;
    for (Leaf leaf : tree.leaves) {
        leaf.internode = new_index[static_cast<std::size_t>(leaf.internode)];
        if (leaf.internode >= 0) leaves.push_back(leaf);
    }
    tree.skeleton = std::move(pruned);
    tree.node_level = std::move(level);
    tree.internode_start_radius = std::move(start_radius);
    tree.leaves = std::move(leaves);
}

}  // namespace treelobes::synth
