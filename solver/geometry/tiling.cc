#include "solver/geometry/tiling.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "solver/geometry/topology.h"

namespace systole::geometry {

double max_edge_mm(const TriMesh& mesh) {
  double l = 0;
  for (const auto& t : mesh.tri)
    for (int k = 0; k < 3; ++k)
      l = std::max(l, (mesh.position_mm[t[k]] - mesh.position_mm[t[(k + 1) % 3]]).norm());
  return l;
}

int tiling_level(const TriMesh& mesh, double max_spacing_mm) {
  if (!(max_spacing_mm > 0)) throw std::invalid_argument("tiling_level: spacing must be > 0");
  return std::max(1, static_cast<int>(std::ceil(max_edge_mm(mesh) / max_spacing_mm - 1e-12)));
}

TriMesh tile(const TriMesh& mesh, int m) {
  if (m < 1) throw std::invalid_argument("tile: m must be >= 1");
  if (m == 1) return mesh;
  const EdgeTopology topo(mesh);
  const std::size_t n0 = mesh.node_count(), ne = topo.edge_count(), nt = mesh.triangle_count();
  const std::size_t interior_per_tri = static_cast<std::size_t>((m - 1) * (m - 2) / 2);
  TriMesh out;
  out.name = mesh.name;
  out.kind = mesh.kind;
  const std::size_t total_nodes = n0 + ne * (m - 1) + nt * interior_per_tri;
  out.position_mm.reserve(total_nodes);
  out.region.reserve(total_nodes);
  out.position_mm = mesh.position_mm;
  out.region = mesh.region;
  // Edge nodes: edge e, k = 1..m-1 at edge[e][0] + k/m (edge[e][1] - edge[e][0]).
  const auto edge_base = static_cast<std::int32_t>(n0);
  // Points are computed from the lexicographically smaller end position, so that two bodies
  // sharing a ring (same positions) and tiled at the same level get bitwise identical nodes.
  auto lex_less = [](const Vec3& p, const Vec3& q) {
    return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
  };
  for (std::size_t e = 0; e < ne; ++e) {
    const auto [a, b] = topo.edge[e];
    const Vec3 pa = mesh.position_mm[a], pb = mesh.position_mm[b];
    const std::uint32_t r = mesh.region[a] & mesh.region[b];
    const bool forward = !lex_less(pb, pa);
    const Vec3 &p0 = forward ? pa : pb, &p1 = forward ? pb : pa;
    for (int k = 1; k < m; ++k) {
      const int kk = forward ? k : m - k;
      out.add_node(p0 + (p1 - p0) * (static_cast<double>(kk) / m), r);
    }
  }
  const std::size_t tiles = nt * static_cast<std::size_t>(m) * m;
  out.tri.reserve(tiles);
  out.tissue.reserve(tiles);
  out.thickness_mm.reserve(tiles);
  out.fibre.reserve(tiles);
  std::vector<std::int32_t> lattice(static_cast<std::size_t>((m + 1) * (m + 2) / 2));
  auto lat = [&](int i, int j) -> std::int32_t& {  // i + j <= m
    // row j holds m + 1 - j points
    const int offset = j * (m + 1) - j * (j - 1) / 2;
    return lattice[offset + i];
  };
  for (std::size_t t = 0; t < nt; ++t) {
    const auto [a, b, c] = mesh.tri[t];
    const Vec3 pa = mesh.position_mm[a], pb = mesh.position_mm[b], pc = mesh.position_mm[c];
    // Edge node of the triangle edge from node u to node v at fraction k/m from u.
    auto edge_node = [&](int local, std::int32_t u, int k) {
      const auto e = topo.face_edge[t][local];
      const int kk = topo.edge[e][0] == u ? k : m - k;
      return edge_base + static_cast<std::int32_t>(e) * (m - 1) + (kk - 1);
    };
    const std::uint32_t rin = mesh.region[a] & mesh.region[b] & mesh.region[c];
    for (int j = 0; j <= m; ++j)
      for (int i = 0; i + j <= m; ++i) {
        std::int32_t id;
        if (i == 0 && j == 0) id = a;
        else if (i == m && j == 0) id = b;
        else if (i == 0 && j == m) id = c;
        else if (j == 0) id = edge_node(0, a, i);          // edge a -> b
        else if (i + j == m) id = edge_node(1, b, j);      // edge b -> c
        else if (i == 0) id = edge_node(2, c, m - j);      // edge c -> a
        else
          id = out.add_node(pa + (pb - pa) * (static_cast<double>(i) / m) +
                                (pc - pa) * (static_cast<double>(j) / m),
                            rin);
        lat(i, j) = id;
      }
    for (int j = 0; j < m; ++j)
      for (int i = 0; i + j < m; ++i) {
        out.add_triangle(lat(i, j), lat(i + 1, j), lat(i, j + 1), mesh.tissue[t], mesh.thickness_mm[t],
                         mesh.fibre[t]);
        if (i + j + 1 < m)
          out.add_triangle(lat(i + 1, j), lat(i + 1, j + 1), lat(i, j + 1), mesh.tissue[t],
                           mesh.thickness_mm[t], mesh.fibre[t]);
      }
  }
  return out;
}

TilingMap tiling_map(const TriMesh& mesh, int m) {
  if (m < 1) throw std::invalid_argument("tiling_map: m must be >= 1");
  TilingMap map;
  map.m = m;
  auto add = [&](std::array<std::int32_t, 3> p, std::array<double, 3> w, int n) {
    map.parent.push_back(p);
    map.weight.push_back(w);
    map.count.push_back(static_cast<std::uint8_t>(n));
  };
  const std::size_t n0 = mesh.node_count();
  for (std::size_t n = 0; n < n0; ++n) add({static_cast<std::int32_t>(n), 0, 0}, {1.0, 0.0, 0.0}, 1);
  if (m == 1) return map;
  // The numbering of tile(): edge nodes edge by edge (k = 1..m-1 at k/m from edge[e][0]: tile()
  // computes the point from the lexicographically smaller end, the same point), then each
  // triangle's interior lattice points row by row.
  const EdgeTopology topo(mesh);
  for (std::size_t e = 0; e < topo.edge_count(); ++e) {
    const auto [a, b] = topo.edge[e];
    for (int k = 1; k < m; ++k) {
      const double f = static_cast<double>(k) / m;
      add({a, b, 0}, {1.0 - f, f, 0.0}, 2);
    }
  }
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto [a, b, c] = mesh.tri[t];
    for (int j = 1; j < m; ++j)
      for (int i = 1; i + j < m; ++i) {
        const double fi = static_cast<double>(i) / m, fj = static_cast<double>(j) / m;
        add({a, b, c}, {1.0 - fi - fj, fi, fj}, 3);
      }
  }
  return map;
}

std::vector<Vec3> TilingMap::interpolate(const std::vector<Vec3>& parent_values) const {
  std::vector<Vec3> out(size(), Vec3::Zero());
  for (std::size_t n = 0; n < size(); ++n)
    for (int k = 0; k < count[n]; ++k) out[n] += weight[n][k] * parent_values.at(parent[n][k]);
  return out;
}

std::vector<Vec3> TilingMap::spread(const std::vector<Vec3>& tiled_values, std::size_t parent_count) const {
  if (tiled_values.size() != size())
    throw std::invalid_argument("TilingMap::spread: " + std::to_string(tiled_values.size()) + " values for " +
                                std::to_string(size()) + " tiled nodes");
  std::vector<Vec3> out(parent_count, Vec3::Zero());
  for (std::size_t n = 0; n < size(); ++n)
    for (int k = 0; k < count[n]; ++k) out.at(parent[n][k]) += weight[n][k] * tiled_values[n];
  return out;
}

}  // namespace systole::geometry
