#pragma once
// Low-level meshing kernels used by the procedural heart (internal to solver/geometry).
// - delaunay_2d: Bowyer-Watson Delaunay triangulation of planar points (expected O(n log n):
//   points inserted in a serpentine grid order, located by walking from the last triangle).
// - stitch_rings / close_with_pole: triangulate the band between two closed node rings of
//   different sizes by merging them in angle order (O(n_a + n_b)).
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "solver/geometry/tri_mesh.h"

namespace systole::geometry::detail {

using Vec2 = Eigen::Vector2d;

// Counter-clockwise triangles covering the convex hull of `points` (indices into `points`).
// Points must be distinct; exact co-circularity is tolerated (ties broken arbitrarily).
std::vector<Tri> delaunay_2d(const std::vector<Vec2>& points);

// A closed ring of mesh nodes, ordered by increasing angle; angle[i] in radians, increasing,
// spanning less than 2*pi (node ids index the body's TriMesh).
struct Ring {
  std::vector<std::int32_t> node;
  std::vector<double> angle;
};

// Appends the triangles of the band between rings a and b. Orientation: (a_i, a_i+1, b_j),
// i.e. with angles increasing counter-clockwise about an axis t pointing from a to b, the
// normal points away from the axis. Returns the number of triangles appended.
std::size_t stitch_rings(const Ring& a, const Ring& b, std::vector<Tri>& out);
// Fan from the ring to a pole node beyond it (same orientation rule as stitch_rings(a, pole)).
std::size_t close_with_pole(const Ring& a, std::int32_t pole, std::vector<Tri>& out);

// Hexagonal lattice of spacing h covering [lo, hi], with a deterministic tiny jitter
// (1e-3 h) that removes exact co-circularity for the Delaunay step.
std::vector<Vec2> hex_lattice(const Vec2& lo, const Vec2& hi, double h);

// Cumulative arclength resampling: given a densely sampled curve (values of a scalar
// parameter and the cumulative arclength at each sample), the parameter values of n + 1
// equally spaced stations from the first to the last sample.
std::vector<double> equal_arclength_stations(const std::vector<double>& param,
                                             const std::vector<double>& arclength, int n);

}  // namespace systole::geometry::detail
