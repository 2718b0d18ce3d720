#include "solver/ibm/shapes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

namespace systole::ibm {

using geometry::Tissue;
using Eigen::Vector3d;

geometry::TriMesh sphere_mesh(const Vector3d& centre_mm, double radius_mm, int subdivisions) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vector3d> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                             {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Vector3d& q : p) q.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back((p[a] + p[b]).normalized());
      return mid[key] = static_cast<int>(p.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  geometry::TriMesh m;
  m.name = "sphere";
  m.kind = geometry::BodyKind::kRigid;
  for (const Vector3d& q : p) m.add_node(centre_mm + radius_mm * q);
  for (const auto& tri : f) {
    const Vector3d n = (p[tri[1]] - p[tri[0]]).cross(p[tri[2]] - p[tri[0]]);
    if (n.dot(p[tri[0]] + p[tri[1]] + p[tri[2]]) > 0)
      m.add_triangle(tri[0], tri[1], tri[2], Tissue::kValvularPlane, 1.0);
    else
      m.add_triangle(tri[0], tri[2], tri[1], Tissue::kValvularPlane, 1.0);
  }
  return m;
}

geometry::TriMesh tube_mesh(double x0_mm, double length_mm, double axis_y_mm, double axis_z_mm, double radius_mm,
                            int n_axial, int n_around) {
  geometry::TriMesh m;
  m.name = "tube";
  m.kind = geometry::BodyKind::kVessel;
  const double two_pi = 2 * std::numbers::pi;
  for (int a = 0; a <= n_axial; ++a)
    for (int r = 0; r < n_around; ++r) {
      const double th = two_pi * r / n_around;
      m.add_node({x0_mm + length_mm * a / n_axial, axis_y_mm + radius_mm * std::cos(th),
                  axis_z_mm + radius_mm * std::sin(th)});
    }
  auto id = [&](int a, int r) { return a * n_around + (r % n_around); };
  for (int a = 0; a < n_axial; ++a)
    for (int r = 0; r < n_around; ++r) {
      // (a,r) → (a+1,r) → (a,r+1): normal = e_x × e_θ = −e_r (into the lumen). (Fixed
      // 2026-12-01: the previous order gave e_θ × e_x = +e_r, outward, against the contract.)
      m.add_triangle(id(a, r), id(a + 1, r), id(a, r + 1), Tissue::kAorticWall, 1.0);
      m.add_triangle(id(a, r + 1), id(a + 1, r), id(a + 1, r + 1), Tissue::kAorticWall, 1.0);
    }
  return m;
}

geometry::TriMesh plate_with_hole_mesh(double x0_mm, double y0_mm, double side_mm, double z_mm, double hole_radius_mm,
                                       int n_radial, int n_around) {
  geometry::TriMesh m;
  m.name = "plate";
  m.kind = geometry::BodyKind::kRigid;
  const double cx = x0_mm + side_mm / 2, cy = y0_mm + side_mm / 2, half = side_mm / 2;
  const double two_pi = 2 * std::numbers::pi;
  for (int s = 0; s <= n_radial; ++s)
    for (int r = 0; r < n_around; ++r) {
      const double th = two_pi * r / n_around, c = std::cos(th), sn = std::sin(th);
      const double edge = half / std::max(std::abs(c), std::abs(sn));  // square boundary
      const double rho = hole_radius_mm + (edge - hole_radius_mm) * s / n_radial;
      m.add_node({cx + rho * c, cy + rho * sn, z_mm});
    }
  auto id = [&](int s, int r) { return s * n_around + (r % n_around); };
  for (int s = 0; s < n_radial; ++s)
    for (int r = 0; r < n_around; ++r) {
      // (s,r) → (s+1,r) → (s,r+1): e_ρ × e_θ = +z.
      m.add_triangle(id(s, r), id(s + 1, r), id(s, r + 1), Tissue::kValvularPlane, 1.0);
      m.add_triangle(id(s, r + 1), id(s + 1, r), id(s + 1, r + 1), Tissue::kValvularPlane, 1.0);
    }
  return m;
}

geometry::TriMesh perforated_plate_x_mesh(double x_mm, double y0_mm, double ly_mm, double z0_mm, double lz_mm,
                                          double yc_mm, double zc_mm, double hole_radius_mm, int ny, int nz,
                                          PlatePart part) {
  geometry::TriMesh m;
  m.name = part == PlatePart::plate ? "orifice plate" : "orifice cover";
  m.kind = geometry::BodyKind::kRigid;
  auto node = [&](int j, int k) { return Eigen::Vector3d(x_mm, y0_mm + ly_mm * j / ny, z0_mm + lz_mm * k / nz); };
  std::map<int, std::int32_t> used;  // grid node → mesh node (only the nodes of kept triangles)
  auto id = [&](int j, int k) {
    const int key = k * (ny + 1) + j;
    auto it = used.find(key);
    if (it != used.end()) return it->second;
    const std::int32_t n = m.add_node(node(j, k));
    used.emplace(key, n);
    return n;
  };
  auto keep = [&](const Eigen::Vector3d& c) {
    const bool inside = std::hypot(c.y() - yc_mm, c.z() - zc_mm) < hole_radius_mm;
    return part == PlatePart::cover ? inside : !inside;
  };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      // (j,k) → (j+1,k) → (j+1,k+1): e_y × e_z = +x; and (j,k) → (j+1,k+1) → (j,k+1).
      const int tri[2][3][2] = {{{j, k}, {j + 1, k}, {j + 1, k + 1}}, {{j, k}, {j + 1, k + 1}, {j, k + 1}}};
      for (const auto& t : tri) {
        const Eigen::Vector3d c = (node(t[0][0], t[0][1]) + node(t[1][0], t[1][1]) + node(t[2][0], t[2][1])) / 3.0;
        if (!keep(c)) continue;
        m.add_triangle(id(t[0][0], t[0][1]), id(t[1][0], t[1][1]), id(t[2][0], t[2][1]), Tissue::kValvularPlane, 1.0);
      }
    }
  return m;
}

geometry::TriMesh plate_mesh(double x0_mm, double y0_mm, double lx_mm, double ly_mm, double z_mm, int nx, int ny) {
  geometry::TriMesh m;
  m.name = "plate";
  m.kind = geometry::BodyKind::kRigid;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.add_node({x0_mm + lx_mm * i / nx, y0_mm + ly_mm * j / ny, z_mm});
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.add_triangle(id(i, j), id(i + 1, j), id(i + 1, j + 1), Tissue::kValvularPlane, 1.0);  // +z
      m.add_triangle(id(i, j), id(i + 1, j + 1), id(i, j + 1), Tissue::kValvularPlane, 1.0);
    }
  return m;
}

}  // namespace systole::ibm
