#include "geometry/closed_mesh.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <unordered_map>

namespace treelobes {

namespace {

std::uint64_t directed_key(int a, int b) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

int origin_of(const TriangleMesh& mesh, int half_edge) { return mesh.faces[half_edge / 3][half_edge % 3]; }
int target_of(const TriangleMesh& mesh, int half_edge) { return mesh.faces[half_edge / 3][(half_edge % 3 + 1) % 3]; }
int third_of(const TriangleMesh& mesh, int half_edge) { return mesh.faces[half_edge / 3][(half_edge % 3 + 2) % 3]; }

// Half-edges of one undirected edge {a < b}: `forward` run a -> b, `backward` run b -> a.
struct EdgeFan {
    std::vector<int> forward, backward;
};

std::unordered_map<std::uint64_t, EdgeFan> edge_fans(const TriangleMesh& mesh) {
    std::unordered_map<std::uint64_t, EdgeFan> fans;
    fans.reserve(mesh.faces.size() * 2);
    for (int h = 0; h < static_cast<int>(mesh.faces.size() * 3); ++h) {
        const int a = origin_of(mesh, h), b = target_of(mesh, h);
        auto& fan = fans[directed_key(std::min(a, b), std::max(a, b))];
        (a < b ? fan.forward : fan.backward).push_back(h);
    }
    return fans;
}

// Pairs the 2k faces around edge a -> b (a < b) by angle about the edge. The outward normal of a
// face running a -> b points toward increasing angle (right-hand rule about b - a), so the solid
// sector lies just below it; a face running b -> a has the solid just above it. Each backward
// face is therefore paired with the next face counter-clockwise, which closes the same solid
// sector. Returns false if the order does not alternate (numerically flat configurations).
bool pair_fan(const TriangleMesh& mesh, int a, int b, const EdgeFan& fan, std::vector<int>& opposite) {
    const Eigen::Vector3d pa = mesh.vertices[a].cast<double>();
    const Eigen::Vector3d axis = (mesh.vertices[b].cast<double>() - pa).normalized();
    Eigen::Vector3d u = axis.unitOrthogonal();
    const Eigen::Vector3d v = axis.cross(u);
    struct Entry {
        double angle;
        int half_edge;
        bool backward;
    };
    std::vector<Entry> entries;
    auto add = [&](int h, bool backward) {
        const Eigen::Vector3d r = mesh.vertices[third_of(mesh, h)].cast<double>() - pa;
        entries.push_back({std::atan2(r.dot(v), r.dot(u)), h, backward});
    };
    for (int h : fan.forward) add(h, false);
    for (int h : fan.backward) add(h, true);
    std::sort(entries.begin(), entries.end(),
              [](const Entry& x, const Entry& y) { return x.angle != y.angle ? x.angle < y.angle : x.half_edge < y.half_edge; });
    const std::size_t n = entries.size();
    for (std::size_t i = 0; i < n; ++i)
        if (entries[i].backward == entries[(i + 1) % n].backward) return false;
    for (std::size_t i = 0; i < n; ++i) {
        if (!entries[i].backward) continue;
        const int h = entries[i].half_edge, g = entries[(i + 1) % n].half_edge;
        opposite[h] = g;
        opposite[g] = h;
    }
    return true;
}

// Any pairing of forward with backward half-edges is still closed and oriented; used when the
// angular order is ambiguous.
void pair_in_order(const EdgeFan& fan, std::vector<int>& opposite) {
    for (std::size_t i = 0; i < fan.forward.size(); ++i) {
        opposite[fan.forward[i]] = fan.backward[i];
        opposite[fan.backward[i]] = fan.forward[i];
    }
}

// Gives every fan of faces around a vertex (an orbit of "previous half-edge, then opposite")
// its own vertex; the first fan met keeps the original index.
void split_vertex_fans(TriangleMesh& mesh, const std::vector<int>& opposite) {
    const int half_edges = static_cast<int>(mesh.faces.size() * 3);
    std::vector<char> visited(half_edges, 0);
    std::vector<char> claimed(mesh.vertices.size(), 0);
    std::vector<std::array<int, 3>> faces = mesh.faces;
    for (int start = 0; start < half_edges; ++start) {
        if (visited[start]) continue;
        const int vertex = origin_of(mesh, start);
        int copy = vertex;
        if (claimed[vertex]) {
            copy = static_cast<int>(mesh.vertices.size());
            mesh.vertices.push_back(mesh.vertices[vertex]);
        }
        claimed[vertex] = 1;
        int h = start;
        do {
            visited[h] = 1;
            faces[h / 3][h % 3] = copy;
            const int previous = (h / 3) * 3 + (h % 3 + 2) % 3;  // ends at `vertex`
            h = opposite[previous];                              // starts at `vertex`
        } while (h != start && h >= 0 && !visited[h]);
    }
    mesh.faces = std::move(faces);
}

}  // namespace

ClosedMeshReport check_closed(const TriangleMesh& mesh) {
    ClosedMeshReport report;
    std::unordered_map<std::uint64_t, int> use;
    use.reserve(mesh.faces.size() * 3);
    for (const auto& f : mesh.faces) {
        if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) ++report.degenerate_faces;
        for (int k = 0; k < 3; ++k) ++use[directed_key(f[k], f[(k + 1) % 3])];
    }
    for (const auto& [key, count] : use) {
        if (count > 1) ++report.repeated_half_edges;
        const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
        const auto twin = use.find(directed_key(b, a));
        if (twin == use.end() || twin->second != count) report.unpaired_half_edges += static_cast<std::size_t>(count);
    }
    return report;
}

std::vector<int> opposite_half_edges(const TriangleMesh& mesh) {
    std::unordered_map<std::uint64_t, int> by_key;
    by_key.reserve(mesh.faces.size() * 3);
    for (int h = 0; h < static_cast<int>(mesh.faces.size() * 3); ++h)
        by_key.emplace(directed_key(origin_of(mesh, h), target_of(mesh, h)), h);
    std::vector<int> opposite(mesh.faces.size() * 3, -1);
    for (int h = 0; h < static_cast<int>(opposite.size()); ++h) {
        const auto it = by_key.find(directed_key(target_of(mesh, h), origin_of(mesh, h)));
        if (it != by_key.end()) opposite[h] = it->second;
    }
    return opposite;
}

bool make_closed_manifold(TriangleMesh& mesh) {
    const auto fans = edge_fans(mesh);
    std::vector<int> opposite(mesh.faces.size() * 3, -1);
    for (const auto& [key, fan] : fans) {
        if (fan.forward.size() != fan.backward.size()) return false;
        if (fan.forward.size() == 1) {
            opposite[fan.forward[0]] = fan.backward[0];
            opposite[fan.backward[0]] = fan.forward[0];
            continue;
        }
        const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
        if (!pair_fan(mesh, a, b, fan, opposite)) pair_in_order(fan, opposite);
    }
    split_vertex_fans(mesh, opposite);
    return true;
}

void remove_unused_vertices(TriangleMesh& mesh) {
    std::vector<int> index(mesh.vertices.size(), -1);
    std::vector<Eigen::Vector3f> kept;
    kept.reserve(mesh.vertices.size());
    for (auto& f : mesh.faces)
        for (int& v : f) {
            if (index[v] < 0) {
                index[v] = static_cast<int>(kept.size());
                kept.push_back(mesh.vertices[v]);
            }
            v = index[v];
        }
    mesh.vertices = std::move(kept);
}

std::vector<int> face_components(const TriangleMesh& mesh, int* count) {
    const std::vector<int> opposite = opposite_half_edges(mesh);
    std::vector<int> component(mesh.faces.size(), -1);
    int next = 0;
    std::vector<int> stack;
    for (std::size_t seed = 0; seed < mesh.faces.size(); ++seed) {
        if (component[seed] >= 0) continue;
        component[seed] = next;
        stack.assign(1, static_cast<int>(seed));
        while (!stack.empty()) {
            const int f = stack.back();
            stack.pop_back();
            for (int k = 0; k < 3; ++k) {
                const int o = opposite[f * 3 + k];
                if (o >= 0 && component[o / 3] < 0) {
                    component[o / 3] = next;
                    stack.push_back(o / 3);
                }
            }
        }
        ++next;
    }
    if (count) *count = next;
    return component;
}

}  // namespace treelobes
