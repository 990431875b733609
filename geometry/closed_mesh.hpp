// Closed, consistently oriented triangle surfaces: the form every lobe takes (Livny et al. 2011, §4.2).
//
// The boundary of a union of solid cells (the regular facets of an alpha shape) is an oriented
// triangle soup in which each edge is used as often in one direction as in the other. Where two
// solid parts touch along an edge or at a vertex, that soup is not a 2-manifold: an edge has 4,
// 6, ... faces, or the faces around a vertex form several fans. make_closed_manifold() pairs
// the faces around such an edge geometrically (each face with its neighbour across the solid
// sector it bounds) and gives each fan of a vertex its own copy of the vertex. The result is a
// closed 2-manifold (every half-edge has exactly one opposite half-edge) with the input's
// outward orientation, which mesh simplification, the .tlobe coder and inside tests rely on.
#pragma once

#include "core/triangle_mesh.hpp"

#include <cstddef>
#include <vector>

namespace treelobes {

struct ClosedMeshReport {
    std::size_t unpaired_half_edges = 0;  // half-edges without an opposite (holes, flipped faces)
    std::size_t repeated_half_edges = 0;  // directed edges used by more than one face (non-manifold)
    std::size_t degenerate_faces = 0;     // faces repeating a vertex index
    bool closed() const { return unpaired_half_edges == 0 && repeated_half_edges == 0 && degenerate_faces == 0; }
};

// Combinatorial check: closed and consistently oriented when every directed edge appears once
// and its reverse appears once.
ClosedMeshReport check_closed(const TriangleMesh& mesh);

// Opposite half-edge of every half-edge (index 3 * face + corner, the edge from corner k to
// k + 1) of a closed 2-manifold; -1 where there is none.
std::vector<int> opposite_half_edges(const TriangleMesh& mesh);

// Turns a balanced oriented soup (see above) into a closed 2-manifold. Returns false and leaves
// the mesh unchanged when the soup is not balanced (some edge has more faces in one direction).
bool make_closed_manifold(TriangleMesh& mesh);

// Drops vertices no face uses and renumbers the rest in order of first use.
void remove_unused_vertices(TriangleMesh& mesh);

// Connected components through shared edges (face -> component id, ids from 0 in face order).
std::vector<int> face_components(const TriangleMesh& mesh, int* count = nullptr);

}  // namespace treelobes
