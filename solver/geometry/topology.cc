#include "solver/geometry/topology.h"

#include <algorithm>
#include <unordered_map>

namespace systole::geometry {

EdgeTopology::EdgeTopology(const TriMesh& mesh) {
  const std::size_t m = mesh.triangle_count();
  struct Half {
    std::int32_t a, b;  // sorted
    std::int32_t face;
    std::int8_t local;
  };
  std::vector<Half> half;
  half.reserve(3 * m);
  for (std::size_t f = 0; f < m; ++f)
    for (int k = 0; k < 3; ++k) {
      std::int32_t a = mesh.tri[f][k], b = mesh.tri[f][(k + 1) % 3];
      if (a > b) std::swap(a, b);
      half.push_back({a, b, static_cast<std::int32_t>(f), static_cast<std::int8_t>(k)});
    }
  std::sort(half.begin(), half.end(), [](const Half& x, const Half& y) {
    return x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.face < y.face);
  });
  face_edge.assign(m, {-1, -1, -1});
  edge_face_offset.push_back(0);
  edge_face.reserve(half.size());
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    const auto e = static_cast<std::int32_t>(edge.size());
    edge.push_back({half[i].a, half[i].b});
    while (j < half.size() && half[j].a == half[i].a && half[j].b == half[i].b) {
      edge_face.push_back(half[j].face);
      face_edge[half[j].face][half[j].local] = e;
      ++j;
    }
    edge_face_offset.push_back(static_cast<std::int32_t>(edge_face.size()));
    i = j;
  }
}

bool EdgeTopology::traverses_forward(const TriMesh& mesh, std::size_t f, std::int32_t a,
                                     std::int32_t b) {
  const auto& t = mesh.tri[f];
  for (int k = 0; k < 3; ++k)
    if (t[k] == a && t[(k + 1) % 3] == b) return true;
  return false;
}

std::vector<std::vector<std::int32_t>> boundary_loops(const TriMesh& mesh, const EdgeTopology& topo) {
  std::unordered_multimap<std::int32_t, std::int32_t> next;  // directed boundary edges
  for (std::size_t e = 0; e < topo.edge_count(); ++e) {
    if (topo.face_count_of(e) != 1) continue;
    const auto f = topo.edge_face[topo.edge_face_offset[e]];
    auto [a, b] = topo.edge[e];
    if (!EdgeTopology::traverses_forward(mesh, f, a, b)) std::swap(a, b);
    next.emplace(a, b);
  }
  std::vector<std::vector<std::int32_t>> loops;
  while (!next.empty()) {
    auto it = next.begin();
    const std::int32_t start = it->first;
    std::vector<std::int32_t> loop{start};
    std::int32_t cur = it->second;
    next.erase(it);
    while (cur != start) {
      loop.push_back(cur);
      auto nx = next.find(cur);
      if (nx == next.end()) break;  // open chain (non-manifold boundary): stop here
      cur = nx->second;
      next.erase(nx);
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

}  // namespace systole::geometry
