#include "geometry/branch_mesh.hpp"

#include "core/error.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>
#include <numbers>

namespace treelobes {

namespace {

using Vec3 = Eigen::Vector3f;

// One axis: a root-to-tip or fork-to-tip path that follows the main child.
struct Axis {
    std::vector<int> nodes;  // nodes[0] is the root or the fork node on the parent axis
    bool lateral = false;
};

// One ring position along an axis curve.
struct Sample {
    Vec3 position;
    float radius;
    int node;  // the tree node this sample sits on, -1 between nodes
};

void check_options(const BranchMeshOptions& o) {
    if (o.sides < 3 || o.sides > 64) throw Error::usage("branch mesh: sides must be in 3..64, got " + std::to_string(o.sides));
    if (o.subdivisions < 1 || o.subdivisions > 16)
        throw Error::usage("branch mesh: subdivisions must be in 1..16, got " + std::to_string(o.subdivisions));
    if (!(o.min_radius > 0.0f) || !std::isfinite(o.min_radius)) throw Error::usage("branch mesh: min_radius must be > 0");
    if (!(o.radius_scale > 0.0f) || !std::isfinite(o.radius_scale)) throw Error::usage("branch mesh: radius_scale must be > 0");
    if (!(o.min_axis_radius >= 0.0f)) throw Error::usage("branch mesh: min_axis_radius must be >= 0");
}

// Follows main children from `start` to a tip.
std::vector<int> follow_main_children(const TreeGraph& tree, int start) {
    std::vector<int> path{start};
    while (!tree.nodes[path.back()].children.empty()) path.push_back(tree.nodes[path.back()].children.front());
    return path;
}

// Axes in breadth-first order so a parent axis is always meshed before its laterals (their
// first frame is derived from the parent's frame at the fork).
std::vector<Axis> split_into_axes(const TreeGraph& tree) {
    std::vector<Axis> axes;
    std::deque<Axis> queue;
    queue.push_back({follow_main_children(tree, 0), false});
    while (!queue.empty()) {
        Axis axis = std::move(queue.front());
        queue.pop_front();
        for (std::size_t i = axis.lateral ? 1 : 0; i < axis.nodes.size(); ++i) {
            const auto& children = tree.nodes[axis.nodes[i]].children;
            for (std::size_t k = 1; k < children.size(); ++k) {
                Axis lateral{{axis.nodes[i]}, true};
                const std::vector<int> rest = follow_main_children(tree, children[k]);
                lateral.nodes.insert(lateral.nodes.end(), rest.begin(), rest.end());
                queue.push_back(std::move(lateral));
            }
        }
        axes.push_back(std::move(axis));
    }
    return axes;
}

// Centripetal Catmull-Rom point between p1 and p2 (Barry-Goldman pyramid); never overshoots
// into loops or cusps, unlike the uniform variant, when neighbouring internodes differ a lot.
Vec3 catmull_rom(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, float u) {
    auto knot = [](const Vec3& a, const Vec3& b) { return std::max(std::sqrt((b - a).norm()), 1e-6f); };
    const float t0 = 0, t1 = t0 + knot(p0, p1), t2 = t1 + knot(p1, p2), t3 = t2 + knot(p2, p3);
    const float t = t1 + u * (t2 - t1);
    const Vec3 a1 = ((t1 - t) * p0 + (t - t0) * p1) / (t1 - t0);
    const Vec3 a2 = ((t2 - t) * p1 + (t - t1) * p2) / (t2 - t1);
    const Vec3 a3 = ((t3 - t) * p2 + (t - t2) * p3) / (t3 - t2);
    const Vec3 b1 = ((t2 - t) * a1 + (t - t0) * a2) / (t2 - t0);
    const Vec3 b2 = ((t3 - t) * a2 + (t - t1) * a3) / (t3 - t1);
    return ((t2 - t) * b1 + (t - t1) * b2) / (t2 - t1);
}

// Samples of one axis: nodes closer than a micrometre to the previous one are merged (their
// samples are shared), then each internode gets `subdivisions` rings along the smooth curve.
std::vector<Sample> sample_axis(const TreeGraph& tree, const Axis& axis, const BranchMeshOptions& o,
                                std::vector<std::pair<int, int>>& merged) {
    std::vector<Vec3> points;
    std::vector<float> radii;
    std::vector<int> nodes;
    for (std::size_t i = 0; i < axis.nodes.size(); ++i) {
        const TreeNode& node = tree.nodes[axis.nodes[i]];
        float radius = std::max(o.min_radius, node.radius * o.radius_scale);
        if (i == 0 && axis.lateral) {
            // The lateral's base ring has the lateral's radius, capped by the parent's, so that it
            // stays inside the parent tube.
            const TreeNode& first = tree.nodes[axis.nodes[1]];
            radius = std::min(radius, std::max(o.min_radius, first.radius * o.radius_scale));
        }
        if (!points.empty() && (node.position - points.back()).norm() < 1e-6f) {
            merged.emplace_back(axis.nodes[i], nodes.back());
            continue;
        }
        points.push_back(node.position);
        radii.push_back(radius);
        nodes.push_back(axis.nodes[i]);
    }
    std::vector<Sample> samples;
    if (points.size() < 2) return samples;
    const std::size_t m = points.size() - 1;
    auto at = [&](long i) -> Vec3 {  // reflected phantom points beyond both ends
        if (i < 0) return 2.0f * points[0] - points[1];
        if (i > static_cast<long>(m)) return 2.0f * points[m] - points[m - 1];
        return points[i];
    };
    for (std::size_t k = 0; k < m; ++k) {
        for (int j = 0; j < o.subdivisions; ++j) {
            const float u = static_cast<float>(j) / static_cast<float>(o.subdivisions);
            const long i = static_cast<long>(k);
            const Vec3 p = j == 0 ? points[k] : catmull_rom(at(i - 1), at(i), at(i + 1), at(i + 2), u);
            samples.push_back({p, radii[k] + u * (radii[k + 1] - radii[k]), j == 0 ? nodes[k] : -1});
        }
    }
    samples.push_back({points[m], radii[m], nodes[m]});
    return samples;
}

// Tangents: direction of the chord through the neighbours (the bisector at a bend), one-sided at the ends.
std::vector<Vec3> sample_tangents(const std::vector<Sample>& s) {
    std::vector<Vec3> t(s.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
        const Vec3& prev = s[i == 0 ? 0 : i - 1].position;
        const Vec3& next = s[i + 1 == s.size() ? i : i + 1].position;
        Vec3 d = next - prev;
        if (i > 0 && i + 1 < s.size()) {
            // Bisector of the two unit directions, robust to very unequal sample spacing.
            const Vec3 a = (s[i].position - prev).normalized(), b = (next - s[i].position).normalized();
            if ((a + b).norm() > 1e-3f) d = a + b;
        }
        t[i] = d.norm() > 0 ? d.normalized() : (i > 0 ? t[i - 1] : Vec3::UnitZ());
    }
    return t;
}

// A unit vector perpendicular to t, chosen deterministically.
Vec3 any_perpendicular(const Vec3& t) {
    const Vec3 axis = std::abs(t.x()) <= std::abs(t.y()) && std::abs(t.x()) <= std::abs(t.z()) ? Vec3::UnitX()
                      : std::abs(t.y()) <= std::abs(t.z())                                     ? Vec3::UnitY()
                                                                                               : Vec3::UnitZ();
    return t.cross(axis).normalized();
}

// The minimal rotation taking unit vector `from` to `to`, applied to `v`.
Vec3 rotate_minimally(const Vec3& v, const Vec3& from, const Vec3& to) {
    const Vec3 axis = from.cross(to);
    const float s = axis.norm(), c = from.dot(to);
    if (s < 1e-7f) return c > 0 ? v : -v;  // parallel: keep; antiparallel: half turn (any axis in the plane)
    return Eigen::AngleAxisf(std::atan2(s, c), axis / s) * v;
}

// Rotation-minimizing frame normals by the double reflection method (Wang et al. 2008).
std::vector<Vec3> transport_normals(const std::vector<Sample>& s, const std::vector<Vec3>& t, Vec3 first) {
    std::vector<Vec3> n(s.size());
    n[0] = (first - first.dot(t[0]) * t[0]).normalized();
    for (std::size_t i = 0; i + 1 < s.size(); ++i) {
        const Vec3 v1 = s[i + 1].position - s[i].position;
        const float c1 = v1.squaredNorm();
        Vec3 next = n[i];
        if (c1 > 1e-14f) {
            const Vec3 r_l = n[i] - (2.0f / c1) * v1.dot(n[i]) * v1;
            const Vec3 t_l = t[i] - (2.0f / c1) * v1.dot(t[i]) * v1;
            const Vec3 v2 = t[i + 1] - t_l;
            const float c2 = v2.squaredNorm();
            next = c2 > 1e-14f ? Vec3(r_l - (2.0f / c2) * v2.dot(r_l) * v2) : r_l;
        }
        next -= next.dot(t[i + 1]) * t[i + 1];  // remove float drift
        n[i + 1] = next.norm() > 1e-6f ? next.normalized() : any_perpendicular(t[i + 1]);
    }
    return n;
}

// Appends the rings, side quads and caps of one tube.
void emit_tube(const std::vector<Sample>& s, const std::vector<Vec3>& t, const std::vector<Vec3>& n, const BranchMeshOptions& o,
               TriangleMesh& mesh) {
    const int sides = o.sides;
    const int first = static_cast<int>(mesh.vertices.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
        const Vec3 b = t[i].cross(n[i]);
        for (int j = 0; j < sides; ++j) {
            const float a = 2.0f * std::numbers::pi_v<float> * static_cast<float>(j) / static_cast<float>(sides);
            mesh.vertices.push_back(s[i].position + s[i].radius * (std::cos(a) * n[i] + std::sin(a) * b));
        }
    }
    auto v = [&](std::size_t ring, int j) { return first + static_cast<int>(ring) * sides + (j % sides); };
    for (std::size_t i = 0; i + 1 < s.size(); ++i)
        for (int j = 0; j < sides; ++j) {
            // Counter-clockwise seen from outside: (a, b, c) has normal (T x R) x T = R, outward.
            mesh.faces.push_back({v(i, j), v(i, j + 1), v(i + 1, j + 1)});
            mesh.faces.push_back({v(i, j), v(i + 1, j + 1), v(i + 1, j)});
        }
    if (!o.cap_ends) return;
    const int base = static_cast<int>(mesh.vertices.size());
    mesh.vertices.push_back(s.front().position);
    const int tip = base + 1;
    mesh.vertices.push_back(s.back().position);
    const std::size_t last = s.size() - 1;
    for (int j = 0; j < sides; ++j) {
        mesh.faces.push_back({base, v(0, j + 1), v(0, j)});       // faces -T
        mesh.faces.push_back({tip, v(last, j), v(last, j + 1)});  // faces +T
    }
}

}  // namespace

TriangleMesh build_branch_mesh(const TreeGraph& tree, const BranchMeshOptions& options) {
    check_options(options);
    TriangleMesh mesh;
    mesh.origin = tree.origin;
    if (tree.size() < 2) return mesh;
    tree.validate("branch mesh");

    // Frame normal at each node, recorded on the axis that passes through it, for the laterals.
    std::vector<Vec3> node_normal(tree.size(), Vec3::Zero());
    std::vector<Vec3> node_tangent(tree.size(), Vec3::Zero());
    std::vector<bool> skipped(tree.size(), false);
    for (const Axis& axis : split_into_axes(tree)) {
        const int fork = axis.nodes.front();
        if (axis.lateral && skipped[fork]) {
            for (int node : axis.nodes) skipped[node] = true;
            continue;
        }
        std::vector<std::pair<int, int>> merged;  // (node, earlier node at the same position)
        const std::vector<Sample> samples = sample_axis(tree, axis, options, merged);
        const bool too_thin = !samples.empty() && samples.front().radius < options.min_axis_radius;
        if (samples.empty() || too_thin) {
            for (std::size_t i = axis.lateral ? 1 : 0; i < axis.nodes.size(); ++i) skipped[axis.nodes[i]] = too_thin;
            continue;
        }
        const std::vector<Vec3> tangents = sample_tangents(samples);
        Vec3 first_normal = any_perpendicular(tangents.front());
        if (axis.lateral && node_tangent[fork].squaredNorm() > 0)
            first_normal = rotate_minimally(node_normal[fork], node_tangent[fork], tangents.front());
        const std::vector<Vec3> normals = transport_normals(samples, tangents, first_normal);
        for (std::size_t i = 0; i < samples.size(); ++i) {
            const int node = samples[i].node;
            if (node < 0 || (axis.lateral && node == fork)) continue;
            node_normal[node] = normals[i];
            node_tangent[node] = tangents[i];
        }
        // A node merged into its predecessor shares that node's frame.
        for (const auto& [node, previous] : merged) {
            node_normal[node] = node_normal[previous];
            node_tangent[node] = node_tangent[previous];
        }
        emit_tube(samples, tangents, normals, options, mesh);
    }
    return mesh;
}

}  // namespace treelobes
