#pragma once
// Edge topology of a TriMesh: unique edges, edge -> faces (CSR), face -> edges, boundary
// loops. Built in O(n log n) by sorting half-edge keys; valid for non-manifold input too
// (the quality checks use it to find such edges).
#include <array>
#include <cstdint>
#include <vector>

#include "solver/geometry/tri_mesh.h"

namespace systole::geometry {

struct EdgeTopology {
  std::vector<std::array<std::int32_t, 2>> edge;  // node pair, edge[e][0] < edge[e][1]
  std::vector<std::array<std::int32_t, 3>> face_edge;  // edge of (v0,v1), (v1,v2), (v2,v0)
  std::vector<std::int32_t> edge_face_offset;     // CSR, size edges + 1
  std::vector<std::int32_t> edge_face;            // faces of edge e: [offset[e], offset[e+1])

  explicit EdgeTopology(const TriMesh& mesh);

  std::size_t edge_count() const { return edge.size(); }
  int face_count_of(std::size_t e) const { return edge_face_offset[e + 1] - edge_face_offset[e]; }
  // True if face f traverses edge e from edge[e][0] to edge[e][1].
  static bool traverses_forward(const TriMesh& mesh, std::size_t f, std::int32_t a, std::int32_t b);
};

// Closed loops of boundary edges (edges with one face), each as a node sequence in the
// direction its face traverses it. Nodes where several boundary loops touch are handled by
// consuming edges greedily.
std::vector<std::vector<std::int32_t>> boundary_loops(const TriMesh& mesh, const EdgeTopology& topo);

}  // namespace systole::geometry
