#pragma once
// Second-order MAC difference operators, named for the location of their result
// (ARCHITECTURE.md rule 6). All act on this rank's interior and read one halo layer; the
// caller has exchanged halos and applied wall conditions. The discrete Laplacian of the
// pressure solver equals divergence ∘ gradient, which is what makes the projection exact.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "solver/grid/grid.h"

namespace systole::fluid {

// div_at_cell = (u(i+1)−u(i))/Δx + (v(j+1)−v(j))/Δy + (w(k+1)−w(k))/Δz, interior cells.
inline void divergence_at_cell(const grid::Grid& g, const grid::XFaceField& u, const grid::YFaceField& v,
                               const grid::ZFaceField& w, double scale, grid::CellField& out) {
  const double idx = scale / g.dx(), idy = scale / g.dy(), idz = scale / g.dz();
  const auto sj = u.stride_j(), sk = u.stride_k();
  for (int k = 0; k < u.k_count(); ++k)
    for (int j = 0; j < u.ny(); ++j) {
      const auto row = u.index(0, j, k);
      const double* pu = u.data() + row;
      const double* pv = v.data() + row;
      const double* pw = w.data() + row;
      double* po = out.data() + row;
      for (int i = 0; i < u.nx(); ++i)
        po[i] = (pu[i + 1] - pu[i]) * idx + (pv[i + sj] - pv[i]) * idy + (pw[i + sk] - pw[i]) * idz;
    }
}

// Largest |div| over this rank's cells (local; reduce over ranks for the global value).
inline double max_abs_divergence_local(const grid::Grid& g, const grid::XFaceField& u,
                                       const grid::YFaceField& v, const grid::ZFaceField& w) {
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const auto sj = u.stride_j(), sk = u.stride_k();
  double m = 0;
  for (int k = 0; k < u.k_count(); ++k)
    for (int j = 0; j < u.ny(); ++j) {
      const auto row = u.index(0, j, k);
      const double* pu = u.data() + row;
      const double* pv = v.data() + row;
      const double* pw = w.data() + row;
      for (int i = 0; i < u.nx(); ++i)
        m = std::max(m, std::abs((pu[i + 1] - pu[i]) * idx + (pv[i + sj] - pv[i]) * idy +
                                 (pw[i + sk] - pw[i]) * idz));
    }
  return m;
}

// u −= c ∂φ/∂x at x-faces, v −= c ∂φ/∂y at y-faces, w −= c ∂φ/∂z at z-faces (interior z-faces
// only: the wall faces k = 0 and nz keep their prescribed value). φ needs its halos.
inline void subtract_gradient_at_faces(const grid::Slabs& s, const grid::CellField& phi, double c,
                                       grid::XFaceField& u, grid::YFaceField& v, grid::ZFaceField& w) {
  const grid::Grid& g = s.grid();
  const double cx = c / g.dx(), cy = c / g.dy(), cz = c / g.dz();
  const auto sj = phi.stride_j(), sk = phi.stride_k();
  for (int k = 0; k < u.k_count(); ++k) {
    const bool wall_face = (s.k_begin() + k == 0);
    for (int j = 0; j < u.ny(); ++j) {
      const auto row = u.index(0, j, k);
      const double* pp = phi.data() + row;
      double* pu = u.data() + row;
      double* pv = v.data() + row;
      double* pw = w.data() + row;
      for (int i = 0; i < u.nx(); ++i) {
        pu[i] -= cx * (pp[i] - pp[i - 1]);
        pv[i] -= cy * (pp[i] - pp[i - sj]);
      }
      if (!wall_face)
        for (int i = 0; i < u.nx(); ++i) pw[i] -= cz * (pp[i] - pp[i - sk]);
    }
  }
}

// γ̇² = 2 S:S, S = ½(∇u + ∇uᵀ), at the centre of the cell with storage index q (all fields share
// one layout; sj, sk its strides). The diagonal of S from the face differences across the cell;
// each off-diagonal 2S_ab from its value at the four cell edges around the centre, averaged
// (second order). Reads one halo layer: valid halos and wall ghosts are the caller's.
inline double strain_rate_squared_at_cell(const double* u, const double* v, const double* w, std::ptrdiff_t q,
                                          std::ptrdiff_t sj, std::ptrdiff_t sk, double idx, double idy,
                                          double idz) {
  const double sxx = (u[q + 1] - u[q]) * idx, syy = (v[q + sj] - v[q]) * idy, szz = (w[q + sk] - w[q]) * idz;
  // 2S_xy at the xy-edge of storage index e (x = x_i, y = y_j): ∂u/∂y + ∂v/∂x.
  auto exy = [&](std::ptrdiff_t e) { return (u[e] - u[e - sj]) * idy + (v[e] - v[e - 1]) * idx; };
  auto exz = [&](std::ptrdiff_t e) { return (u[e] - u[e - sk]) * idz + (w[e] - w[e - 1]) * idx; };
  auto eyz = [&](std::ptrdiff_t e) { return (v[e] - v[e - sk]) * idz + (w[e] - w[e - sj]) * idy; };
  const double gxy = 0.25 * (exy(q) + exy(q + 1) + exy(q + sj) + exy(q + 1 + sj));
  const double gxz = 0.25 * (exz(q) + exz(q + 1) + exz(q + sk) + exz(q + 1 + sk));
  const double gyz = 0.25 * (eyz(q) + eyz(q + sj) + eyz(q + sk) + eyz(q + sj + sk));
  return 2 * (sxx * sxx + syy * syy + szz * szz) + gxy * gxy + gxz * gxz + gyz * gyz;
}

// The velocity gradient α_ij = ∂u_j/∂x_i at the centre of the cell with storage index q, as
// grad[3 i + j]: the diagonal from the face differences across the cell, each off-diagonal
// derivative from its value at the four cell edges around the centre, averaged (the same
// averages as strain_rate_squared_at_cell, whose off-diagonals are α_ij + α_ji). Reads one
// halo layer: valid halos and wall ghosts are the caller's.
inline std::array<double, 9> velocity_gradient_at_cell(const double* u, const double* v, const double* w,
                                                       std::ptrdiff_t q, std::ptrdiff_t sj, std::ptrdiff_t sk,
                                                       double idx, double idy, double idz) {
  // Σ over the four edges e of f(e) − f(e − back): an edge-averaged difference (× ¼ below).
  auto edges = [&](const double* f, std::ptrdiff_t back, std::ptrdiff_t s1, std::ptrdiff_t s2) {
    double sum = 0;
    for (std::ptrdiff_t e : {q, q + s1, q + s2, q + s1 + s2}) sum += f[e] - f[e - back];
    return 0.25 * sum;
  };
  std::array<double, 9> a;
  a[0] = (u[q + 1] - u[q]) * idx;       // ∂u/∂x
  a[4] = (v[q + sj] - v[q]) * idy;      // ∂v/∂y
  a[8] = (w[q + sk] - w[q]) * idz;      // ∂w/∂z
  a[3] = edges(u, sj, 1, sj) * idy;     // ∂u/∂y at the xy-edges
  a[1] = edges(v, 1, 1, sj) * idx;      // ∂v/∂x at the xy-edges
  a[6] = edges(u, sk, 1, sk) * idz;     // ∂u/∂z at the xz-edges
  a[2] = edges(w, 1, 1, sk) * idx;      // ∂w/∂x at the xz-edges
  a[7] = edges(v, sk, sj, sk) * idz;    // ∂v/∂z at the yz-edges
  a[5] = edges(w, sj, sj, sk) * idy;    // ∂w/∂y at the yz-edges
  return a;
}

}  // namespace systole::fluid
