// Small trees with known structure for the export tests.
#pragma once

#include "core/tree_graph.hpp"
#include "core/triangle_mesh.hpp"

namespace treelobes::test {

// A georeferenced tree (UTM-sized origin): a 3 m trunk of 4 internodes, a lateral from the
// second trunk node (1.5 m up) with a sub-lateral, and a lateral from the third trunk node.
//   nodes 0-4 trunk (z 0, 0.75, 1.5, 2.25, 3), 5-7 first lateral, 8 its sub-lateral, 9-10 second lateral.
inline TreeGraph sample_tree(const Eigen::Vector3d& origin = {500000.0, 5400000.0, 300.0}) {
    TreeGraph t;
    t.origin = origin;
    t.add_node({0, 0, 0}, 0.12f, -1);
    t.add_node({0, 0, 0.75f}, 0.10f, 0);
    t.add_node({0.02f, 0, 1.5f}, 0.09f, 1);
    t.add_node({0.02f, 0.01f, 2.25f}, 0.07f, 2);
    t.add_node({0.03f, 0.01f, 3.0f}, 0.04f, 3);
    t.add_node({0.5f, 0, 1.9f}, 0.04f, 2);  // 5: first lateral
    t.add_node({1.0f, 0.1f, 2.2f}, 0.03f, 5);
    t.add_node({1.4f, 0.1f, 2.6f}, 0.015f, 6);
    t.add_node({1.1f, 0.5f, 2.5f}, 0.01f, 6);   // 8: sub-lateral
    t.add_node({-0.4f, 0.2f, 2.5f}, 0.03f, 3);  // 9: second lateral
    t.add_node({-0.8f, 0.3f, 2.9f}, 0.02f, 9);
    return t;
}

// A closed, outward-oriented octahedron of half-size `r` around `centre` (a lobe stand-in).
inline TriangleMesh octahedron(const Eigen::Vector3f& centre, float r) {
    TriangleMesh m;
    for (const Eigen::Vector3f& d : {Eigen::Vector3f(r, 0, 0), Eigen::Vector3f(-r, 0, 0), Eigen::Vector3f(0, r, 0),
                                     Eigen::Vector3f(0, -r, 0), Eigen::Vector3f(0, 0, r), Eigen::Vector3f(0, 0, -r)})
        m.vertices.push_back(centre + d);
    m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    return m;
}

}  // namespace treelobes::test
