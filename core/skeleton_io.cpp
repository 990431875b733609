#include "core/skeleton_io.hpp"

#include "core/error.hpp"
#include "core/georef_sidecar.hpp"
#include "core/ply_format.hpp"

#include <cmath>
#include <deque>

namespace fs = std::filesystem;

namespace treelobes {

namespace {

const ply::Property* find_any(const ply::Element& element, std::initializer_list<const char*> names) {
    for (const char* name : names)
        if (const auto* p = element.find(name); p && !p->is_list) return p;
    return nullptr;
}

// Edges are read as undirected and oriented away from vertex 0, so files from tools that do
// not orient their edges (AdTree) load too; child order follows the file's edge order.
std::vector<std::vector<int>> adjacency_from_edges(const ply::Element& edges, std::size_t vertex_count, const std::string& name) {
    const auto* from = find_any(edges, {"vertex1", "vertex_index1", "v1"});
    const auto* to = find_any(edges, {"vertex2", "vertex_index2", "v2"});
    if (!from || !to) throw Error::input(name, "skeleton PLY edge element needs properties vertex1 and vertex2");
    std::vector<std::vector<int>> adjacency(vertex_count);
    for (std::size_t i = 0; i < edges.count; ++i) {
        const double a = from->values[i], b = to->values[i];
        if (!(a >= 0 && b >= 0 && a < vertex_count && b < vertex_count) || a != std::floor(a) || b != std::floor(b) || a == b)
            throw Error::input(name, "skeleton edge " + std::to_string(i) + " has invalid vertex indices");
        adjacency[static_cast<std::size_t>(a)].push_back(static_cast<int>(b));
        adjacency[static_cast<std::size_t>(b)].push_back(static_cast<int>(a));
    }
    return adjacency;
}

}  // namespace

TreeGraph read_skeleton_ply(const fs::path& path, std::vector<std::string>* comments) {
    const std::string name = path.string();
    const ply::File file = ply::read(path);
    if (comments) *comments = file.comments;
    const ply::Element* vertex = file.find("vertex");
    if (!vertex || vertex->count == 0) throw Error::input(name, "skeleton PLY has no vertices");
    const auto* x = find_any(*vertex, {"x"});
    const auto* y = find_any(*vertex, {"y"});
    const auto* z = find_any(*vertex, {"z"});
    if (!x || !y || !z) throw Error::input(name, "skeleton PLY vertices lack x, y or z");
    const auto* radius = find_any(*vertex, {"radius", "scalar_radius"});

    const ply::Element* edges = file.find("edge");
    const std::size_t n = vertex->count;
    if ((!edges ? 0 : edges->count) != n - 1)
        throw Error::input(name, "a tree with " + std::to_string(n) + " vertices needs " + std::to_string(n - 1) + " edges, found " +
                                         std::to_string(edges ? edges->count : 0));
    const auto adjacency = edges ? adjacency_from_edges(*edges, n, name) : std::vector<std::vector<int>>(n);

    // Breadth-first from vertex 0, renumbering nothing: node i of the graph is vertex i.
    TreeGraph tree;
    tree.origin = read_origin_comment(file.comments).value_or(Eigen::Vector3d::Zero());
    tree.nodes.resize(n);
    std::vector<bool> seen(n, false);
    std::deque<int> queue{0};
    seen[0] = true;
    while (!queue.empty()) {
        const int u = queue.front();
        queue.pop_front();
        for (int v : adjacency[u]) {
            if (seen[v]) {
                if (tree.nodes[u].parent != v)
                    throw Error::input(name, "skeleton edges contain a cycle (at vertex " + std::to_string(v) + ")");
                continue;
            }
            seen[v] = true;
            tree.nodes[v].parent = u;
            tree.nodes[u].children.push_back(v);
            queue.push_back(v);
        }
    }
    for (std::size_t i = 0; i < n; ++i) {
        if (!seen[i])
            throw Error::input(name, "skeleton is not connected: vertex " + std::to_string(i) + " is not reachable from vertex 0");
        tree.nodes[i].position =
                Eigen::Vector3f(static_cast<float>(x->values[i]), static_cast<float>(y->values[i]), static_cast<float>(z->values[i]));
        tree.nodes[i].radius = radius ? static_cast<float>(radius->values[i]) : 0.0f;
    }
    tree.validate(name);
    return tree;
}

void write_skeleton_ply(const TreeGraph& tree, const fs::path& path, bool binary, const std::vector<std::string>& comments) {
    tree.validate(path.string());
    ply::File file;
    file.format = binary ? "binary_little_endian" : "ascii";
    file.comments.push_back("treelobes skeleton: vertex 0 is the root, edges are parent -> child, main child first");
    write_origin_comment(tree.origin, file.comments);
    file.comments.insert(file.comments.end(), comments.begin(), comments.end());

    ply::Element vertex;
    vertex.name = "vertex";
    vertex.count = tree.size();
    const char* names[4] = {"x", "y", "z", "radius"};
    for (int k = 0; k < 4; ++k) {
        ply::Property p;
        p.name = names[k];
        p.type = AttributeType::Float32;
        for (const auto& node : tree.nodes) p.values.push_back(k < 3 ? node.position[k] : node.radius);
        vertex.properties.push_back(std::move(p));
    }
    ply::Element edge;
    edge.name = "edge";
    edge.count = tree.size() - 1;
    ply::Property from, to;
    from.name = "vertex1";
    to.name = "vertex2";
    from.type = to.type = AttributeType::Int32;
    for (int u : tree.preorder())
        for (int v : tree.nodes[u].children) {
            from.values.push_back(u);
            to.values.push_back(v);
        }
    edge.properties = {std::move(from), std::move(to)};
    file.elements = {std::move(vertex), std::move(edge)};
    ply::write(file, path);
    write_georef_sidecar(path, tree.origin, {});
}

}  // namespace treelobes
