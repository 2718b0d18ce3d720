#include "solver/structure/shapes.h"

#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

namespace systole::structure {

using geometry::Tri;
using geometry::TriMesh;
using geometry::Vec3;

TriMesh icosphere(double radius_mm, int level, double thickness_mm, geometry::Tissue tissue,
                  bool azimuthal_fibres) {
  if (level < 0 || level > 8) throw std::invalid_argument("icosphere: level must be in [0, 8]");
  const double p = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> v{{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                      {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  for (auto& q : v) q.normalize();
  // Outward-oriented faces of the icosahedron.
  std::vector<Tri> f{{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                     {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                     {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      const int id = static_cast<int>(v.size() - 1);
      mid.emplace(key, id);
      return id;
    };
    std::vector<Tri> g;
    g.reserve(f.size() * 4);
    for (const auto& t : f) {
      const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      g.push_back({t[0], ab, ca});
      g.push_back({t[1], bc, ab});
      g.push_back({t[2], ca, bc});
      g.push_back({ab, bc, ca});
    }
    f = std::move(g);
  }
  TriMesh m;
  m.name = "sphere";
  m.kind = geometry::BodyKind::kChamber;
  for (const auto& q : v) m.add_node(radius_mm * q);
  for (const auto& t : f) {
    // Reverse: normals into the cavity.
    const std::int32_t id = m.add_triangle(t[0], t[2], t[1], tissue, thickness_mm);
    if (azimuthal_fibres) {
      const Vec3 c = m.centroid(id);
      m.fibre[id] = geometry::tangent_in_triangle(m, id, Vec3::UnitZ().cross(c), Vec3::UnitX());
    }
  }
  return m;
}

TriMesh flat_sheet(int nx, int ny, double edge_mm, double thickness_mm, geometry::Tissue tissue,
                   const Vec3& fibre) {
  if (nx < 2 || ny < 2) throw std::invalid_argument("flat_sheet: need nx, ny >= 2");
  TriMesh m;
  m.name = "sheet";
  m.kind = geometry::BodyKind::kLeaflet;
  const double dy = edge_mm * std::sqrt(3.0) / 2;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.add_node(Vec3((i + 0.5 * (j % 2)) * edge_mm, j * dy, 0));
  auto id = [nx](int i, int j) { return j * nx + i; };
  const Vec3 fib = fibre.norm() > 0 ? Vec3(fibre.x(), fibre.y(), 0).normalized() : Vec3::Zero();
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      if (j % 2 == 0) {  // row j unshifted, row j+1 shifted right
        m.add_triangle(id(i, j), id(i + 1, j), id(i, j + 1), tissue, thickness_mm, fib);
        m.add_triangle(id(i + 1, j), id(i + 1, j + 1), id(i, j + 1), tissue, thickness_mm, fib);
      } else {  // row j shifted right, row j+1 unshifted
        m.add_triangle(id(i, j), id(i + 1, j + 1), id(i, j + 1), tissue, thickness_mm, fib);
        m.add_triangle(id(i, j), id(i + 1, j), id(i + 1, j + 1), tissue, thickness_mm, fib);
      }
    }
  }
  return m;
}

}  // namespace systole::structure
