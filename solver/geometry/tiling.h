#pragma once
// Quadratic tiling (MODEL.md §4): every triangle is split into m^2 similar tiles by dividing
// each edge into m equal parts. Edge nodes are shared between neighbouring triangles, so the
// tiled mesh is conforming; the new nodes lie in the parent's plane, so the area is kept
// exactly (up to round-off). Tiles keep the parent's tissue, thickness and fibre; a new node
// carries the regions common to the parent nodes it lies between (AND of their tags), so an
// anchor ring stays an anchor ring and region patches keep their interior.
#include <array>
#include <cstdint>
#include <vector>

#include "solver/geometry/tri_mesh.h"

namespace systole::geometry {

// The tiled mesh (m >= 1; m = 1 returns a copy). O(n log n) (edge topology) + O(n m^2).
TriMesh tile(const TriMesh& mesh, int m);

// Where each node of tile(mesh, m) comes from: node n = Σ_k weight[n][k] · parent node
// parent[n][k] (k < count[n]; weights ≥ 0 summing to 1), the linear interpolation inside the
// parent triangle. The tiled positions are this map applied to the parent positions (to
// round-off: tile() evaluates them in its own order). Its transpose spreads nodal forces of the
// tiled mesh back to the parents conserving the total force and moment, as the IB needs between
// the structure's mesh and the marker mesh (ours). Same node numbering as tile().
struct TilingMap {
  int m = 1;
  std::vector<std::array<std::int32_t, 3>> parent;
  std::vector<std::array<double, 3>> weight;
  std::vector<std::uint8_t> count;  // 1 (a parent node), 2 (an edge node) or 3 (interior)
  std::size_t size() const { return parent.size(); }
  // y_tiled = P x_parent (positions, velocities).
  std::vector<Vec3> interpolate(const std::vector<Vec3>& parent_values) const;
  // f_parent = Pᵀ f_tiled (forces), sized parent_count.
  std::vector<Vec3> spread(const std::vector<Vec3>& tiled_values, std::size_t parent_count) const;
};
TilingMap tiling_map(const TriMesh& mesh, int m);

// Longest edge of the mesh (mm).
double max_edge_mm(const TriMesh& mesh);

// Smallest m such that every tiled edge is <= max_spacing_mm: ceil(max_edge / spacing).
int tiling_level(const TriMesh& mesh, double max_spacing_mm);

// The marker spacing target: marker_spacing_fraction * Eulerian spacing.
inline double marker_spacing_target_mm(double eulerian_spacing_mm, double fraction) {
  return fraction * eulerian_spacing_mm;
}

}  // namespace systole::geometry
