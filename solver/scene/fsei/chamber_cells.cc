#include "solver/scene/fsei/chamber_cells.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace systole::scene {

std::vector<char> chamber_cells(const std::vector<geometry::Vec3>& x_mm, const std::vector<geometry::Tri>& tri,
                                double plane_z_mm, int side, int nx, int ny, int k_begin, int k_count, double hx_mm,
                                double hy_mm, double hz_mm) {
  if (side != 1 && side != -1) throw std::invalid_argument("chamber_cells: side must be +1 or -1");
  if (nx <= 0 || ny <= 0 || k_count < 0 || !(hx_mm > 0 && hy_mm > 0 && hz_mm > 0))
    throw std::invalid_argument("chamber_cells: a grid of positive size and spacing is needed");
  // the columns' (x, y), shifted off the mesh's edges and vertices (ours: a general position)
  const double sx = 1e-7 * std::sqrt(2.0) * hx_mm, sy = 1e-7 * std::sqrt(3.0) * hy_mm;
  auto column_x = [&](int i) { return (i + 0.5) * hx_mm + sx; };
  auto column_y = [&](int j) { return (j + 0.5) * hy_mm + sy; };
  std::vector<std::vector<double>> crossings(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  for (const geometry::Tri& t : tri) {
    const geometry::Vec3 &a = x_mm[static_cast<std::size_t>(t[0])], &b = x_mm[static_cast<std::size_t>(t[1])],
                         &c = x_mm[static_cast<std::size_t>(t[2])];
    const double area2 = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (area2 == 0) continue;  // vertical in projection: no column crosses it in general position
    const int i0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}) / hx_mm - 0.5)));
    const int i1 = std::min(nx - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}) / hx_mm - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}) / hy_mm - 0.5)));
    const int j1 = std::min(ny - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}) / hy_mm - 0.5)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double px = column_x(i), py = column_y(j);
        // barycentric coordinates of the column in the projected triangle
        const double wa = ((b.x() - px) * (c.y() - py) - (c.x() - px) * (b.y() - py)) / area2;
        const double wb = ((c.x() - px) * (a.y() - py) - (a.x() - px) * (c.y() - py)) / area2;
        const double wc = 1 - wa - wb;
        if (wa < 0 || wb < 0 || wc < 0) continue;
        crossings[static_cast<std::size_t>(j) * nx + i].push_back(wa * a.z() + wb * b.z() + wc * c.z());
      }
  }
  std::vector<char> mask(static_cast<std::size_t>(k_count) * ny * nx, 0);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      std::vector<double>& z = crossings[static_cast<std::size_t>(j) * nx + i];
      if (z.empty()) continue;
      std::sort(z.begin(), z.end());
      for (int k = k_begin; k < k_begin + k_count; ++k) {
        const double zc = (k + 0.5) * hz_mm;
        if (side * (zc - plane_z_mm) <= 0) continue;
        // crossings beyond the centre, away from the plane
        const std::size_t beyond = side > 0 ? static_cast<std::size_t>(z.end() - std::upper_bound(z.begin(), z.end(), zc))
                                            : static_cast<std::size_t>(std::lower_bound(z.begin(), z.end(), zc) - z.begin());
        if (beyond % 2 == 1) mask[(static_cast<std::size_t>(k - k_begin) * ny + j) * nx + i] = 1;
      }
    }
  return mask;
}

std::vector<char> heart_chambers_cells(const std::vector<geometry::Vec3>& lv_x_mm, const std::vector<geometry::Tri>& lv_tri,
                                       const std::vector<geometry::Vec3>& la_x_mm, const std::vector<geometry::Tri>& la_tri,
                                       double plane_z_mm, int lv_side, int nx, int ny, int k_begin, int k_count,
                                       double hx_mm, double hy_mm, double hz_mm) {
  std::vector<char> in = chamber_cells(lv_x_mm, lv_tri, plane_z_mm, lv_side, nx, ny, k_begin, k_count, hx_mm, hy_mm, hz_mm);
  const std::vector<char> in_la =
      chamber_cells(la_x_mm, la_tri, plane_z_mm, -lv_side, nx, ny, k_begin, k_count, hx_mm, hy_mm, hz_mm);
  for (std::size_t c = 0; c < in.size(); ++c) in[c] = static_cast<char>(in[c] || in_la[c]);
  return in;
}

}  // namespace systole::scene
