#pragma once
// Quadratic tiling (MODEL.md §4): every triangle is split into m^2 similar tiles by dividing
// each edge into m equal parts. Edge nodes are shared between neighbouring triangles, so the
// tiled mesh is conforming; the new nodes lie in the parent's plane, so the area is kept
// exactly (up to round-off). Tiles keep the parent's tissue, thickness and fibre; a new node
// carries the regions common to the parent nodes it lies between (AND of their tags), so an
// anchor ring stays an anchor ring and region patches keep their interior.
#include "solver/geometry/tri_mesh.h"

namespace systole::geometry {

// The tiled mesh (m >= 1; m = 1 returns a copy). O(n log n) (edge topology) + O(n m^2).
TriMesh tile(const TriMesh& mesh, int m);

// Longest edge of the mesh (mm).
double max_edge_mm(const TriMesh& mesh);

// Smallest m such that every tiled edge is <= max_spacing_mm: ceil(max_edge / spacing).
int tiling_level(const TriMesh& mesh, double max_spacing_mm);

// The marker spacing target: marker_spacing_fraction * Eulerian spacing.
inline double marker_spacing_target_mm(double eulerian_spacing_mm, double fraction) {
  return fraction * eulerian_spacing_mm;
}

}  // namespace systole::geometry
