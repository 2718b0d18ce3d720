#include "solver/ibm/mls.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace systole::ibm {

double mls_weight(double r) {
  if (r <= 0.5) return 2.0 / 3.0 - 4 * r * r + 4 * r * r * r;
  if (r <= 1.0) return 4.0 / 3.0 * (1 - r) * (1 - r) * (1 - r);
  return 0;
}

double mls_weight_derivative(double r) {
  if (r <= 0.5) return -8 * r + 12 * r * r;
  if (r <= 1.0) return -4 * (1 - r) * (1 - r);
  return 0;
}

WallProximityError::WallProximityError(const Eigen::Vector3d& X)
    : std::runtime_error("ibm MLS: singular moment matrix at (" + std::to_string(X[0]) + ", " + std::to_string(X[1]) +
                         ", " + std::to_string(X[2]) + "): the point is too close to a wall"),
      point_(X) {}

namespace {

using grid::Location;

// One direction of a support for one node offset (face: 0, centre: ½), in closed form (mls.h):
// normalised weights ŵ(a), g(a) = m(δ(a) − m)/v and, when asked, their derivatives with respect
// to X_d (grid units). δ(a) = (first + a + offset) − X_d/Δ_d in cells.
using Axis = MlsAxis;

[[noreturn]] void singular(const Eigen::Vector3d& X) { throw WallProximityError(X); }

// The weight and its derivative for 0 ≤ r ≤ 1 without branches (ours, for cost: the two
// outer nodes of a support have r ∈ [¼, ¾], so a branch on r ≤ ½ is mispredicted half the time).
inline void weight_branchless(double r, double& w, double& dw) {
  const double s = 1 - r;
  const double inner = 2.0 / 3.0 - 4 * r * r + 4 * r * r * r, outer = 4.0 / 3.0 * s * s * s;
  const double d_inner = -8 * r + 12 * r * r, d_outer = -4 * s * s;
  const double in = static_cast<double>(r <= 0.5);  // 1 or 0: an arithmetic select (no branch)
  w = outer + in * (inner - outer);
  dw = d_outer + in * (d_inner - d_outer);
}

// valid_lo/hi: node indices inside the fluid (the others get weight 0); periodic directions
// pass the whole int range.
template <bool kDerivatives>
bool axis(double xc, double inv_spacing, double offset, int valid_lo, int valid_hi, Axis& out) {
  // xc = X_d/Δ_d (the caller divides once per direction); inv_spacing = 1/Δ_d.
  const int centre = mls_nearest(xc - offset);
  out.first = centre - 1;
  double delta[3], w[3], dw[3] = {0, 0, 0};
  double s0 = 0, ds0 = 0;
  const double dr = -inv_spacing / kMlsRadiusCells;  // ∂r/∂X_d for δ > 0 (sign(δ) below)
  for (int a = 0; a < 3; ++a) {
    const int idx = out.first + a;
    delta[a] = (idx + offset) - xc;
    const bool valid = idx >= valid_lo && idx <= valid_hi;
    double wa, dwa;
    weight_branchless(std::abs(delta[a]) / kMlsRadiusCells, wa, dwa);
    w[a] = valid ? wa : 0.0;
    if constexpr (kDerivatives) {
      const double sign = delta[a] > 0 ? 1.0 : (delta[a] < 0 ? -1.0 : 0.0);
      dw[a] = valid ? dwa * sign * dr : 0.0;
      ds0 += dw[a];
    }
    s0 += w[a];
  }
  if (!(s0 > 0)) return false;
  const double inv_s0 = 1.0 / s0;
  double m = 0, q = 0;
  for (int a = 0; a < 3; ++a) {
    out.w[a] = w[a] * inv_s0;
    m += out.w[a] * delta[a];
    q += out.w[a] * delta[a] * delta[a];
  }
  const double v = q - m * m;
  if (!(v > 1e-10)) return false;  // fewer than two nodes in the fluid: A singular
  const double inv_v = 1.0 / v;
  for (int a = 0; a < 3; ++a) out.g[a] = m * (delta[a] - m) * inv_v;
  if constexpr (kDerivatives) {
    const double ddelta = -inv_spacing;  // ∂δ/∂X_d
    double dm = ddelta, dq = 2 * m * ddelta;
    for (int a = 0; a < 3; ++a) {
      out.dw[a] = (dw[a] - out.w[a] * ds0) * inv_s0;
      dm += out.dw[a] * delta[a];
      dq += out.dw[a] * delta[a] * delta[a];
    }
    const double dv = dq - 2 * m * dm;
    for (int a = 0; a < 3; ++a) out.dg[a] = (dm * (delta[a] - m) + m * (ddelta - dm) - out.g[a] * dv) * inv_v;
  }
  return true;
}

struct Location1d {
  double offset[3];
  int z_lo;  // first z index in the fluid (z-faces: the wall face 0 is excluded)
};
Location1d location_1d(Location L) {
  return {{L == Location::x_face ? 0.0 : 0.5, L == Location::y_face ? 0.0 : 0.5, L == Location::z_face ? 0.0 : 0.5},
          L == Location::z_face ? 1 : 0};
}

// The six axes of a point (x, y, z directions × face / centre offsets); index [d][centred].
template <bool kDerivatives>
void axes(const grid::Grid& g, const Eigen::Vector3d& X, Axis out[3][2]) {
  constexpr int kAll = -(1 << 30), kAllHi = 1 << 30;
  const double spacing[3] = {g.dx(), g.dy(), g.dz()};
  for (int d = 0; d < 3; ++d) {
    const double xc = X[d] / spacing[d], inv = 1.0 / spacing[d];
    for (int centred = 0; centred < 2; ++centred) {
      const int lo = d < 2 ? kAll : (centred ? 0 : 1), hi = d < 2 ? kAllHi : g.nz() - 1;
      if (!axis<kDerivatives>(xc, inv, centred ? 0.5 : 0.0, lo, hi, out[d][centred])) singular(X);
    }
  }
}

int wrap(int i, int n) { return ((i % n) + n) % n; }

// The support's first node, centre plane and in-fluid planes (MlsStencil or TensorStencil).
template <class Stencil>
void set_indices(const grid::Grid& g, Location L, const Axis& x, const Axis& y, const Axis& z, Stencil& s) {
  s.i0 = wrap(x.first, g.nx());
  s.j0 = wrap(y.first, g.ny());
  s.k0 = z.first;
  s.k_centre = z.first + 1;
  const int lo = location_1d(L).z_lo, hi = g.nz() - 1;
  s.c_begin = 0;
  while (s.c_begin < 3 && s.k0 + s.c_begin < lo) ++s.c_begin;
  s.c_end = 3;
  while (s.c_end > 0 && s.k0 + s.c_end - 1 > hi) --s.c_end;
}

// φ_abc = ŵx ŵy ŵz (1 − gx − gy − gz).
void assemble(const grid::Grid& g, Location L, const Axis& x, const Axis& y, const Axis& z, MlsStencil& s) {
  set_indices(g, L, x, y, z, s);
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const double wyz = y.w[b] * z.w[c], hyz = 1.0 - y.g[b] - z.g[c];
      for (int a = 0; a < 3; ++a) s.phi[a + 3 * b + 9 * c] = x.w[a] * wyz * (hyz - x.g[a]);
    }
}

// φ and ∂φ/∂X_d = ∂ŵ_d (Π_{e≠d} ŵ_e) H − W ∂g_d, W = Πŵ, H = 1 − Σg.
void assemble_gradient(const grid::Grid& g, Location L, const Axis& x, const Axis& y, const Axis& z,
                       MlsGradientStencil& s) {
  set_indices(g, L, x, y, z, s);
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b) {
      const double wyz = y.w[b] * z.w[c], hyz = 1.0 - y.g[b] - z.g[c];
      const double dwy_z = y.dw[b] * z.w[c], wy_dz = y.w[b] * z.dw[c], dgyz[2] = {y.dg[b], z.dg[c]};
      for (int a = 0; a < 3; ++a) {
        const int q = a + 3 * b + 9 * c;
        const double H = hyz - x.g[a], W = x.w[a] * wyz;
        s.phi[q] = W * H;
        s.dphi[0][q] = x.dw[a] * wyz * H - W * x.dg[a];
        s.dphi[1][q] = x.w[a] * dwy_z * H - W * dgyz[0];
        s.dphi[2][q] = x.w[a] * wy_dz * H - W * dgyz[1];
      }
    }
}

// The axis indices [d][centred] of a location: its own direction on faces (0), others centred (1).
void pick(Location L, int& cx, int& cy, int& cz) {
  cx = L == Location::x_face ? 0 : 1;
  cy = L == Location::y_face ? 0 : 1;
  cz = L == Location::z_face ? 0 : 1;
}

// The three 1-D axes of location L at X (x, y periodic; z bounded by the walls), with the
// derivative weights when Grad.
template <bool Grad>
void axes_at(const grid::Grid& g, Location L, const Eigen::Vector3d& X, Axis (&ax)[3]) {
  const Location1d l = location_1d(L);
  const double spacing[3] = {g.dx(), g.dy(), g.dz()};
  constexpr int kAll = -(1 << 30), kAllHi = 1 << 30;
  for (int d = 0; d < 3; ++d) {
    const int lo = d < 2 ? kAll : l.z_lo, hi = d < 2 ? kAllHi : g.nz() - 1;
    if (!axis<Grad>(X[d] / spacing[d], 1.0 / spacing[d], l.offset[d], lo, hi, ax[d])) singular(X);
  }
}

}  // namespace

MlsStencil mls_stencil(const grid::Grid& g, Location L, const Eigen::Vector3d& X) {
  Axis ax[3];
  axes_at<false>(g, L, X, ax);
  MlsStencil s;
  assemble(g, L, ax[0], ax[1], ax[2], s);
  return s;
}

MlsGradientStencil mls_gradient_stencil(const grid::Grid& g, Location L, const Eigen::Vector3d& X) {
  Axis ax[3];
  axes_at<true>(g, L, X, ax);
  MlsGradientStencil s;
  assemble_gradient(g, L, ax[0], ax[1], ax[2], s);
  return s;
}

void mls_face_stencils(const grid::Grid& g, const Eigen::Vector3d& X, std::array<MlsStencil, 3>& out) {
  Axis ax[3][2];
  axes<false>(g, X, ax);
  const Location where[3] = {Location::x_face, Location::y_face, Location::z_face};
  for (int c = 0; c < 3; ++c) {
    int cx, cy, cz;
    pick(where[c], cx, cy, cz);
    assemble(g, where[c], ax[0][cx], ax[1][cy], ax[2][cz], out[static_cast<std::size_t>(c)]);
  }
}

namespace {

// The quadratic B-spline B₂ and the hat B₁ (r in cells).
double bspline_quadratic(double r) {
  r = std::abs(r);
  if (r <= 0.5) return 0.75 - r * r;
  if (r < 1.5) return 0.5 * (1.5 - r) * (1.5 - r);
  return 0;
}

double bspline_hat(double r) {
  r = std::abs(r);
  return r < 1 ? 1 - r : 0;
}

}  // namespace

void divergence_free_face_stencils(const grid::Grid& g, const Eigen::Vector3d& X, std::array<TensorStencil, 3>& out) {
  // The six axes [direction][0: faces (B₂), 1: centres (B₁)], on the same blocks as MLS.
  Axis ax[3][2];
  const double spacing[3] = {g.dx(), g.dy(), g.dz()};
  for (int d = 0; d < 3; ++d) {
    const double xc = X[d] / spacing[d];
    for (int centred = 0; centred < 2; ++centred) {
      const double offset = centred ? 0.5 : 0.0;
      Axis& A = ax[d][centred];
      A.first = mls_nearest(xc - offset) - 1;
      const int lo = d < 2 ? -(1 << 30) : (centred ? 0 : 1), hi = d < 2 ? (1 << 30) : g.nz() - 1;
      for (int a = 0; a < 3; ++a) {
        const int idx = A.first + a;
        const double delta = (idx + offset) - xc;
        A.w[a] = idx >= lo && idx <= hi ? (centred ? bspline_hat(delta) : bspline_quadratic(delta)) : 0.0;
      }
    }
  }
  const Location where[3] = {Location::x_face, Location::y_face, Location::z_face};
  for (int c = 0; c < 3; ++c) {
    int cx, cy, cz;
    pick(where[c], cx, cy, cz);
    const Axis &x = ax[0][cx], &y = ax[1][cy], &z = ax[2][cz];
    TensorStencil& t = out[static_cast<std::size_t>(c)];
    set_indices(g, where[c], x, y, z, t);
    for (int a = 0; a < 3; ++a) {
      t.x[static_cast<std::size_t>(a)] = x.w[a];
      t.y[static_cast<std::size_t>(a)] = y.w[a];
      t.z[static_cast<std::size_t>(a)] = z.w[a];
    }
  }
}

void divergence_free_face_stencils(const grid::Grid& g, const Eigen::Vector3d& X, std::array<MlsStencil, 3>& out) {
  std::array<TensorStencil, 3> t;
  divergence_free_face_stencils(g, X, t);
  for (std::size_t c = 0; c < 3; ++c) {
    const TensorStencil& f = t[c];
    MlsStencil& s = out[c];
    s.i0 = f.i0;
    s.j0 = f.j0;
    s.k0 = f.k0;
    s.k_centre = f.k_centre;
    s.c_begin = f.c_begin;
    s.c_end = f.c_end;
    for (std::size_t k = 0; k < 3; ++k)
      for (std::size_t b = 0; b < 3; ++b)
        for (std::size_t a = 0; a < 3; ++a) s.phi[a + 3 * b + 9 * k] = f.x[a] * f.y[b] * f.z[k];
  }
}

void mls_check_point(const grid::Grid& g, const Eigen::Vector3d& X) {
  Axis a;
  const double xc = X[2] / g.dz(), inv = 1.0 / g.dz();
  for (int centred = 0; centred < 2; ++centred)  // as axes<>() for d = 2
    if (!axis<false>(xc, inv, centred ? 0.5 : 0.0, centred ? 0 : 1, g.nz() - 1, a)) singular(X);
}

MlsPoint mls_point(const grid::Grid& g, const Eigen::Vector3d& X, bool derivatives) {
  MlsPoint P;
  if (derivatives)
    axes<true>(g, X, P.axis);
  else
    axes<false>(g, X, P.axis);
  return P;
}

}  // namespace systole::ibm
