#include "reconstruct/skeleton_eval.hpp"

#include "core/atomic_file.hpp"
#include "core/cloud_io.hpp"
#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/ply_format.hpp"
#include "core/qsm_io.hpp"
#include "core/skeleton_io.hpp"
#include "geometry/kd_tree.hpp"
#include "geometry/union_find.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

// ---- reading ---------------------------------------------------------------------------------

const ply::Property* scalar_property(const ply::Element& e, std::initializer_list<const char*> names) {
    for (const char* name : names)
        if (const auto* p = e.find(name); p && !p->is_list) return p;
    return nullptr;
}

SkeletonGraph read_ply_graph(const fs::path& path) {
    const std::string name = path.string();
    const ply::File file = ply::read(path);
    const ply::Element* vertex = file.find("vertex");
    if (!vertex || vertex->count == 0) throw Error::input(name, "skeleton PLY has no vertices");
    const auto* x = scalar_property(*vertex, {"x"});
    const auto* y = scalar_property(*vertex, {"y"});
    const auto* z = scalar_property(*vertex, {"z"});
    if (!x || !y || !z) throw Error::input(name, "skeleton PLY vertices lack x, y or z");
    const auto* r = scalar_property(*vertex, {"radius", "scalar_radius"});
    const Eigen::Vector3d origin = read_origin_comment(file.comments).value_or(Eigen::Vector3d::Zero());
    SkeletonGraph g;
    g.kind = "skeleton";
    for (std::size_t i = 0; i < vertex->count; ++i) {
        const Eigen::Vector3d p(x->values[i], y->values[i], z->values[i]);
        if (!p.allFinite()) throw Error::input(name, "vertex " + std::to_string(i) + " has a non-finite coordinate");
        g.vertices.push_back(origin + p);
        g.radius.push_back(r ? static_cast<float>(r->values[i]) : 0.0f);
    }
    if (const ply::Element* edge = file.find("edge")) {
        const auto* a = scalar_property(*edge, {"vertex1", "vertex_index1", "v1"});
        const auto* b = scalar_property(*edge, {"vertex2", "vertex_index2", "v2"});
        if (!a || !b) throw Error::input(name, "skeleton PLY edge element needs vertex1 and vertex2");
        for (std::size_t i = 0; i < edge->count; ++i) {
            const double u = a->values[i], v = b->values[i];
            if (!(u >= 0 && v >= 0 && u < static_cast<double>(vertex->count) && v < static_cast<double>(vertex->count)))
                throw Error::input(name, "edge " + std::to_string(i) + " refers to a missing vertex");
            g.edges.emplace_back(static_cast<int>(u), static_cast<int>(v));
        }
    }
    if (g.edges.size() + 1 == g.vertices.size()) {
        try {
            g.tree = read_skeleton_ply(path);
        } catch (const Error&) {
            // Not one tree (cycles, pieces): distances still work, branch detection does not.
        }
    }
    if (r) g.stem = g.tree ? main_stem(*g.tree) : std::vector<StemSample>{{g.vertices[0], g.radius[0]}};
    return g;
}

// Numbers of one text line; separators: whitespace, comma, semicolon.
bool parse_numbers(const std::string& line, std::vector<double>& out) {
    out.clear();
    const char* p = line.data();
    const char* end = p + line.size();
    while (p < end) {
        while (p < end && (std::isspace(static_cast<unsigned char>(*p)) || *p == ',' || *p == ';')) ++p;
        if (p >= end) break;
        double v = 0;
        const auto [next, ec] = std::from_chars(p, end, v);
        if (ec != std::errc() || next == p) return false;
        out.push_back(v);
        p = next;
    }
    return !out.empty();
}

std::vector<std::vector<double>> read_table(const fs::path& path) {
    std::istringstream in(read_file(path));
    std::vector<std::vector<double>> rows;
    std::string line;
    std::vector<double> values;
    std::size_t line_number = 0;
    while (std::getline(in, line)) {
        ++line_number;
        if (line.find_first_not_of(" \t\r") == std::string::npos || line[line.find_first_not_of(" \t")] == '#') continue;
        if (!parse_numbers(line, values)) {
            if (rows.empty() && line_number == 1) continue;  // a header line
            throw Error::input(path.string(), "line " + std::to_string(line_number) + ": expected numbers");
        }
        if (!rows.empty() && values.size() != rows.front().size())
            throw Error::input(path.string(), "line " + std::to_string(line_number) + ": expected " + std::to_string(rows.front().size()) +
                                                      " columns, found " + std::to_string(values.size()));
        for (double v : values)
            if (!std::isfinite(v)) throw Error::input(path.string(), "line " + std::to_string(line_number) + ": non-finite value");
        rows.push_back(values);
    }
    if (rows.empty()) throw Error::input(path.string(), "no data rows");
    return rows;
}

// One segment per cylinder; a child cylinder is linked (without length) to its parent's end.
SkeletonGraph qsm_graph(const QsmModel& model) {
    SkeletonGraph g;
    g.kind = "treeqsm";
    std::vector<const QsmCylinder*> stem;
    for (const auto& c : model.cylinders) {
        const int a = static_cast<int>(g.vertices.size());
        g.vertices.push_back(c.start);
        g.vertices.push_back(c.end());
        g.radius.insert(g.radius.end(), 2, static_cast<float>(c.radius));
        g.edges.emplace_back(a, a + 1);
        if (c.parent >= 0) g.links.emplace_back(a, 2 * c.parent + 1);
        if (c.branch_order == 0) stem.push_back(&c);
    }
    std::stable_sort(stem.begin(), stem.end(),
                     [](const QsmCylinder* a, const QsmCylinder* b) { return a->position_in_branch < b->position_in_branch; });
    for (const QsmCylinder* c : stem) {
        g.stem.push_back({c->start, c->radius});
        g.stem.push_back({c->end(), c->radius});
    }
    return g;
}

SkeletonGraph point_list_graph(const std::vector<std::vector<double>>& rows, const std::string& name) {
    if (rows.front().size() < 3) throw Error::input(name, "a point list needs x y z columns");
    SkeletonGraph g;
    g.kind = "points";
    for (const auto& r : rows) {
        g.vertices.emplace_back(r[0], r[1], r[2]);
        g.radius.push_back(0.0f);
    }
    return g;
}

// ---- sampling and distances ------------------------------------------------------------------

// Samples of a graph in a local float frame (relative to `origin`), each with its segment
// (edge index; -1 for a bare point).
struct Samples {
    std::vector<Eigen::Vector3f> position;
    std::vector<int> segment;
};

Samples sample_graph(const SkeletonGraph& g, const Eigen::Vector3d& origin, double step) {
    Samples s;
    if (g.edges.empty()) {
        for (const auto& v : g.vertices) {
            s.position.push_back((v - origin).cast<float>());
            s.segment.push_back(-1);
        }
        return s;
    }
    std::vector<bool> is_child(g.vertices.size(), false);
    for (const auto& e : g.edges) is_child[e.second] = true;
    for (std::size_t e = 0; e < g.edges.size(); ++e) {
        const Eigen::Vector3d a = g.vertices[g.edges[e].first] - origin, b = g.vertices[g.edges[e].second] - origin;
        const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step)));
        for (int k = is_child[g.edges[e].first] ? 1 : 0; k <= n; ++k) {
            s.position.push_back((a + (b - a) * (static_cast<double>(k) / n)).cast<float>());
            s.segment.push_back(static_cast<int>(e));
        }
    }
    return s;
}

float point_segment_distance(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const Eigen::Vector3f ab = b - a;
    const float l2 = ab.squaredNorm();
    const float t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0f, 1.0f) : 0.0f;
    return (a + t * ab - p).norm();
}

// Nearest distance from query points to a sampled graph: exact point-to-segment distance over
// the segments of the few nearest samples (or the nearest sample for bare points).
class NearestSegment {
public:
    NearestSegment(const SkeletonGraph& g, const Eigen::Vector3d& origin, double step)
            : graph_(g), origin_(origin), samples_(sample_graph(g, origin, step)), index_(samples_.position) {}

    // Distance and the segment (edge index, -1 for points) it was measured to.
    std::pair<float, int> operator()(const Eigen::Vector3f& q, std::vector<int>& found, std::vector<float>& d2) const {
        index_.knn(q, 6, found, d2);
        float best = std::numeric_limits<float>::infinity();
        int segment = -1;
        for (std::size_t j = 0; j < found.size(); ++j) {
            const int e = samples_.segment[found[j]];
            float d = std::sqrt(d2[j]);
            if (e >= 0) {
                const auto [u, v] = graph_.edges[e];
                d = point_segment_distance(q, (graph_.vertices[u] - origin_).cast<float>(), (graph_.vertices[v] - origin_).cast<float>());
            }
            if (d < best) {
                best = d;
                segment = e;
            }
        }
        return {best, segment};
    }
    const Samples& samples() const { return samples_; }

private:
    const SkeletonGraph& graph_;
    Eigen::Vector3d origin_;
    Samples samples_;
    KdTree index_;
};

DistanceStats statistics(std::vector<float> d) {
    DistanceStats s;
    s.samples = d.size();
    if (d.empty()) return s;
    std::sort(d.begin(), d.end());
    double sum = 0;
    for (float v : d) sum += v;
    s.mean = sum / static_cast<double>(d.size());
    s.median = d.size() % 2 ? d[d.size() / 2] : 0.5 * (d[d.size() / 2 - 1] + d[d.size() / 2]);
    s.p95 = d[static_cast<std::size_t>(std::floor(0.95 * static_cast<double>(d.size() - 1)))];
    s.max = d.back();
    return s;
}

std::vector<float> distances(const Samples& from, const NearestSegment& to) {
    std::vector<float> d;
    d.reserve(from.position.size());
    std::vector<int> found;
    std::vector<float> d2;
    for (const auto& p : from.position) d.push_back(to(p, found, d2).first);
    return d;
}

// The stem's radius where it reaches height z, interpolated between the samples around it; the
// radius of the sample nearest in height when the stem does not span z.
std::optional<double> stem_radius_at(const std::vector<StemSample>& stem, double z) {
    if (stem.empty()) return std::nullopt;
    for (std::size_t i = 1; i < stem.size(); ++i) {
        const double z0 = stem[i - 1].position.z(), z1 = stem[i].position.z();
        if (z0 <= z && z <= z1 && z1 > z0) {
            const double t = (z - z0) / (z1 - z0);
            return (1 - t) * stem[i - 1].radius + t * stem[i].radius;
        }
    }
    const auto nearest = std::min_element(stem.begin(), stem.end(), [z](const StemSample& a, const StemSample& b) {
        return std::abs(a.position.z() - z) < std::abs(b.position.z() - z);
    });
    return nearest->radius;
}

// ---- branch detection ------------------------------------------------------------------------

// Axes of a tree: root-to-tip along main children, and for each lateral child fork-to-tip.
std::vector<std::vector<int>> axes_of(const TreeGraph& tree) {
    std::vector<std::vector<int>> axes;
    std::vector<std::vector<int>> pending{{0}};
    while (!pending.empty()) {
        std::vector<int> axis = std::move(pending.back());
        pending.pop_back();
        while (!tree.nodes[axis.back()].children.empty()) {
            const auto& kids = tree.nodes[axis.back()].children;
            for (std::size_t k = 1; k < kids.size(); ++k) pending.push_back({axis.back(), kids[k]});
            axis.push_back(kids.front());
        }
        if (axis.size() >= 2) axes.push_back(std::move(axis));
    }
    return axes;
}

// Fraction of an axis' samples within tolerance of the other skeleton; the tolerance is
// max(match_distance, radius) with the radius from `own_radius` or the matched segment.
// Segments whose child node is not thicker than `min_diameter` are not sampled: a reference
// branch is scored over its part thicker than the threshold, not over the thin twig it tapers into.
double matched_fraction(const TreeGraph& tree, const Eigen::Vector3d& tree_origin, const std::vector<int>& axis,
                        const NearestSegment& other, const SkeletonGraph& other_graph, bool use_own_radius, double min_diameter,
                        const EvalOptions& o, const Eigen::Vector3d& origin) {
    std::size_t total = 0, matched = 0;
    std::vector<int> found;
    std::vector<float> d2;
    for (std::size_t i = 1; i < axis.size(); ++i) {
        const TreeNode &a = tree.nodes[axis[i - 1]], &b = tree.nodes[axis[i]];
        if (min_diameter > 0 && 2.0 * b.radius <= min_diameter) continue;
        const Eigen::Vector3f pa = (tree_origin + a.position.cast<double>() - origin).cast<float>();
        const Eigen::Vector3f pb = (tree_origin + b.position.cast<double>() - origin).cast<float>();
        const int n = std::max(1, static_cast<int>(std::ceil((pb - pa).norm() / o.sample_step)));
        for (int k = 1; k <= n; ++k) {
            const float t = static_cast<float>(k) / static_cast<float>(n);
            const auto [d, segment] = other(pa + t * (pb - pa), found, d2);
            double radius = use_own_radius ? b.radius : (segment >= 0 ? other_graph.radius[other_graph.edges[segment].second] : 0.0);
            ++total;
            matched += d <= std::max(o.match_distance, radius);
        }
    }
    return total ? static_cast<double>(matched) / static_cast<double>(total) : 0.0;
}

double axis_length(const TreeGraph& tree, const std::vector<int>& axis) {
    double l = 0;
    for (std::size_t i = 1; i < axis.size(); ++i) l += (tree.nodes[axis[i]].position - tree.nodes[axis[i - 1]].position).norm();
    return l;
}

BranchDetection detect_branches(const SkeletonGraph& ours, const SkeletonGraph& ref, const NearestSegment& to_ours,
                                const NearestSegment& to_ref, const EvalOptions& o, const Eigen::Vector3d& origin) {
    BranchDetection b;
    for (const auto& axis : axes_of(*ref.tree)) {
        // Thickness of an axis: its first node above the fork.
        if (2.0 * ref.tree->nodes[axis[1]].radius <= o.min_branch_diameter) continue;
        ++b.reference_branches;
        b.detected += matched_fraction(*ref.tree, ref.tree->origin, axis, to_ours, ours, true, o.min_branch_diameter, o, origin) >=
                      o.min_matched_fraction;
    }
    for (const auto& axis : axes_of(*ours.tree)) {
        if (axis_length(*ours.tree, axis) < o.min_branch_length) continue;
        ++b.skeleton_branches;
        b.correct += matched_fraction(*ours.tree, ours.tree->origin, axis, to_ref, ref, false, 0.0, o, origin) >= o.min_matched_fraction;
    }
    b.recall = b.reference_branches ? static_cast<double>(b.detected) / static_cast<double>(b.reference_branches) : 0.0;
    b.precision = b.skeleton_branches ? static_cast<double>(b.correct) / static_cast<double>(b.skeleton_branches) : 0.0;
    return b;
}

}  // namespace

std::vector<StemSample> main_stem(const TreeGraph& tree) {
    std::vector<StemSample> stem;
    if (tree.nodes.empty()) return stem;
    for (int v = 0;; v = tree.nodes[v].children.front()) {
        stem.push_back({tree.origin + tree.nodes[v].position.cast<double>(), tree.nodes[v].radius});
        if (tree.nodes[v].children.empty()) return stem;
    }
}

std::size_t SkeletonGraph::components() const {
    if (kind == "points") return 0;
    UnionFind sets(vertices.size());
    for (const auto& [a, b] : edges) sets.unite(a, b);
    for (const auto& [a, b] : links) sets.unite(a, b);
    std::size_t n = 0;
    for (std::size_t i = 0; i < vertices.size(); ++i) n += sets.find(static_cast<int>(i)) == static_cast<int>(i);
    return n;
}

double SkeletonGraph::total_length() const {
    double l = 0;
    for (const auto& [a, b] : edges) l += (vertices[a] - vertices[b]).norm();
    return l;
}

SkeletonGraph read_skeleton_graph(const fs::path& path, const std::string& kind) {
    if (kind != "auto" && kind != "skeleton" && kind != "treeqsm" && kind != "points")
        throw Error::usage("reference kind must be auto, skeleton, treeqsm or points, got '" + kind + "'");
    if (!fs::is_regular_file(path)) throw Error::input(path.string(), "no such file");
    const bool ply_file = file_extension(path) == "ply";
    if (kind == "skeleton" || (kind == "auto" && ply_file)) return read_ply_graph(path);
    if (ply_file) throw Error::input(path.string(), "a PLY file can only be read as a skeleton");
    if (kind == "treeqsm" || (kind == "auto" && detect_qsm_file(path) != QsmFileKind::None)) return qsm_graph(read_qsm(path));
    return point_list_graph(read_table(path), path.string());
}

SkeletonComparison compare_skeletons(const SkeletonGraph& ours, const SkeletonGraph& ref, const EvalOptions& o) {
    if (ours.vertices.empty() || ref.vertices.empty()) throw Error::input("", "cannot compare an empty skeleton");
    if (!(o.sample_step > 0)) throw Error::usage("eval: the sample step must be > 0");
    if (!(o.breast_height >= 0)) throw Error::usage("eval: the breast height must be >= 0");
    // A common local frame keeps float precision for georeferenced coordinates.
    const Eigen::Vector3d origin = ours.vertices.front();
    const NearestSegment to_ref(ref, origin, o.sample_step);
    const NearestSegment to_ours(ours, origin, o.sample_step);
    SkeletonComparison c;
    c.sample_distances = distances(to_ours.samples(), to_ref);
    for (const auto& p : to_ours.samples().position) c.sample_positions.push_back(origin + p.cast<double>());
    c.to_reference = statistics(c.sample_distances);
    c.from_reference = statistics(distances(to_ref.samples(), to_ours));
    c.length = ours.total_length();
    if (ref.kind != "points") {
        c.reference_length = ref.total_length();
        if (*c.reference_length > 0) c.length_ratio = c.length / *c.reference_length;
    }
    if (!ref.stem.empty()) {
        const double breast_z = ref.stem.front().position.z() + o.breast_height;
        c.trunk_radius = stem_radius_at(ours.stem, breast_z);
        c.reference_trunk_radius = stem_radius_at(ref.stem, breast_z);
    }
    if (c.trunk_radius && c.reference_trunk_radius && *c.reference_trunk_radius > 0)
        c.trunk_radius_error = (*c.trunk_radius - *c.reference_trunk_radius) / *c.reference_trunk_radius;
    c.components = ours.components();
    c.reference_components = ref.components();
    const bool ref_has_radii = ref.tree && std::any_of(ref.radius.begin(), ref.radius.end(), [](float r) { return r > 0; });
    if (ours.tree && ref_has_radii) c.branches = detect_branches(ours, ref, to_ours, to_ref, o, origin);
    return c;
}

}  // namespace treelobes
