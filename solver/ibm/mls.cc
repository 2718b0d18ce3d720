#include "solver/ibm/mls.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

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

namespace {

struct Geometry1d {
  double spacing, offset;  // node i at (i + offset)·spacing
};

// The support, weights and basis values of X for location L: the shared first half of both
// stencils. The weight is a tensor product, W_k = w_x(a) w_y(b) w_z(c), so everything is kept
// per direction (3 values each) and the moment matrix A = Σ W_k p_k p_kᵀ is assembled from 1-D
// sums (ours, for cost: 3×3 one-dimensional sums instead of 27 outer products):
//   S_d^m = Σ_a w_d(a) δ_d(a)^m  →  A_00 = S_x⁰S_y⁰S_z⁰, A_0x = S_x¹S_y⁰S_z⁰,
//   A_xy = S_x¹S_y¹S_z⁰, A_xx = S_x²S_y⁰S_z⁰, …
// Nodes outside the fluid in z get w_z = 0 (they drop out of every sum and of φ).
// delta[d][a] = (x_a,d − X_d)/Δ_d (cells).
struct Support {
  MlsStencil s;
  double delta[3][3]{}, w[3][3]{};
  Eigen::Matrix4d A_inverse;
};

int wrap(int i, int n) { return ((i % n) + n) % n; }

// The moment matrix from per-direction sums S[d][m] (m = 0, 1, 2).
Eigen::Matrix4d moment_matrix(const double S[3][3]) {
  Eigen::Matrix4d A;
  A(0, 0) = S[0][0] * S[1][0] * S[2][0];
  A(0, 1) = S[0][1] * S[1][0] * S[2][0];
  A(0, 2) = S[0][0] * S[1][1] * S[2][0];
  A(0, 3) = S[0][0] * S[1][0] * S[2][1];
  A(1, 1) = S[0][2] * S[1][0] * S[2][0];
  A(1, 2) = S[0][1] * S[1][1] * S[2][0];
  A(1, 3) = S[0][1] * S[1][0] * S[2][1];
  A(2, 2) = S[0][0] * S[1][2] * S[2][0];
  A(2, 3) = S[0][0] * S[1][1] * S[2][1];
  A(3, 3) = S[0][0] * S[1][0] * S[2][2];
  for (int r = 1; r < 4; ++r)
    for (int c = 0; c < r; ++c) A(r, c) = A(c, r);
  return A;
}

Support build_support(const grid::Grid& g, grid::Location L, const Eigen::Vector3d& X) {
  using grid::Location;
  const Geometry1d dim[3] = {{g.dx(), L == Location::x_face ? 0.0 : 0.5},
                             {g.dy(), L == Location::y_face ? 0.0 : 0.5},
                             {g.dz(), L == Location::z_face ? 0.0 : 0.5}};
  int centre[3];
  for (int d = 0; d < 3; ++d) centre[d] = static_cast<int>(std::lround(X[d] / dim[d].spacing - dim[d].offset));
  Support sp;
  sp.s.i0 = wrap(centre[0] - 1, g.nx());
  sp.s.j0 = wrap(centre[1] - 1, g.ny());
  sp.s.k0 = centre[2] - 1;
  sp.s.k_centre = centre[2];
  const int k_lo = L == Location::z_face ? 1 : 0, k_hi = g.nz() - 1;
  double S[3][3] = {};
  for (int d = 0; d < 3; ++d)
    for (int a = 0; a < 3; ++a) {
      const int idx = centre[d] - 1 + a;
      const double delta = (idx + dim[d].offset) - X[d] / dim[d].spacing;
      const bool valid = d < 2 || (idx >= k_lo && idx <= k_hi);
      const double w = valid ? mls_weight(std::abs(delta) / kMlsRadiusCells) : 0.0;
      sp.delta[d][a] = delta;
      sp.w[d][a] = w;
      S[d][0] += w;
      S[d][1] += w * delta;
      S[d][2] += w * delta * delta;
    }
  const Eigen::Matrix4d A = moment_matrix(S);
  bool invertible = false;
  A.computeInverseWithCheck(sp.A_inverse, invertible, 1e-12);
  if (!invertible)
    throw std::logic_error("ibm MLS: singular moment matrix at (" + std::to_string(X[0]) + ", " + std::to_string(X[1]) +
                           ", " + std::to_string(X[2]) + "): the point is too close to a wall");
  return sp;
}

}  // namespace

MlsStencil mls_stencil(const grid::Grid& g, grid::Location L, const Eigen::Vector3d& X) {
  Support sp = build_support(g, L, X);
  const Eigen::Vector4d c = sp.A_inverse.col(0);  // A⁻¹ e₁ (A symmetric): φ_k = (c·p_k) W_k
  for (int cc = 0; cc < 3; ++cc) {
    const double wz = sp.w[2][cc], pz = c[0] + c[3] * sp.delta[2][cc];
    for (int b = 0; b < 3; ++b) {
      const double wyz = sp.w[1][b] * wz, pyz = pz + c[2] * sp.delta[1][b];
      for (int a = 0; a < 3; ++a) sp.s.phi[a + 3 * b + 9 * cc] = (pyz + c[1] * sp.delta[0][a]) * sp.w[0][a] * wyz;
    }
  }
  return sp.s;
}

MlsGradientStencil mls_gradient_stencil(const grid::Grid& g, grid::Location L, const Eigen::Vector3d& X) {
  const Support sp = build_support(g, L, X);
  MlsGradientStencil out;
  static_cast<MlsStencil&>(out) = sp.s;
  const double spacing[3] = {g.dx(), g.dy(), g.dz()};
  const Eigen::Matrix4d& Ai = sp.A_inverse;
  const Eigen::Vector4d c = Ai.col(0);  // A⁻¹ e₁ (A symmetric)
  // ∂w_d/∂X_d per direction: r = |x_k − X|/(2Δ), ∂r/∂X_d = −sign(x_k − X)/(2Δ_d); and the 1-D
  // sums of w and ∂w, so that ∂A/∂X_d is assembled like A with direction d's sums replaced.
  double dw[3][3], S[3][3] = {}, T[3][3] = {};
  for (int d = 0; d < 3; ++d)
    for (int a = 0; a < 3; ++a) {
      const double delta = sp.delta[d][a];
      const double sign = delta > 0 ? 1.0 : (delta < 0 ? -1.0 : 0.0);
      dw[d][a] = sp.w[d][a] == 0 ? 0.0
                                 : mls_weight_derivative(std::abs(delta) / kMlsRadiusCells) *
                                       (-sign / (kMlsRadiusCells * spacing[d]));
      for (int m = 0; m < 3; ++m) {
        const double power = m == 0 ? 1.0 : (m == 1 ? delta : delta * delta);
        S[d][m] += sp.w[d][a] * power;
        T[d][m] += dw[d][a] * power;
      }
    }
  Eigen::RowVector4d cdA_Ai[3];
  for (int d = 0; d < 3; ++d) {
    double Sd[3][3];
    for (int e = 0; e < 3; ++e)
      for (int m = 0; m < 3; ++m) Sd[e][m] = e == d ? T[e][m] : S[e][m];
    cdA_Ai[d] = c.transpose() * moment_matrix(Sd) * Ai;
  }
  // Seven linear forms of p_k = [1, δx, δy, δz] per node: c·p (φ = c·p W), (A⁻¹e_{d+1})·p and
  // (c ∂A_d A⁻¹)·p for d = x, y, z, evaluated plane by plane, row by row (ours, for cost):
  //   ∂φ/∂X_d = (A⁻¹e_{d+1})·p_k W_k/Δ_d + (c·p_k) ∂W_k/∂X_d − (c ∂A_d A⁻¹)·p_k W_k
  double coef[7][4];
  for (int e = 0; e < 4; ++e) {
    coef[0][e] = c[e];
    for (int d = 0; d < 3; ++d) {
      coef[1 + d][e] = Ai(e, d + 1);
      coef[4 + d][e] = cdA_Ai[d][e];
    }
  }
  for (int cc = 0; cc < 3; ++cc) {
    if (sp.w[2][cc] == 0) continue;  // outside the fluid: φ = ∂φ = 0
    double fz[7];
    for (int f = 0; f < 7; ++f) fz[f] = coef[f][0] + coef[f][3] * sp.delta[2][cc];
    for (int b = 0; b < 3; ++b) {
      double fyz[7];
      for (int f = 0; f < 7; ++f) fyz[f] = fz[f] + coef[f][2] * sp.delta[1][b];
      const double wyz = sp.w[1][b] * sp.w[2][cc];
      const double dwyz[3] = {wyz, dw[1][b] * sp.w[2][cc], sp.w[1][b] * dw[2][cc]};  // d = x: times dw_x below
      for (int a = 0; a < 3; ++a) {
        const int q = a + 3 * b + 9 * cc;
        double v[7];
        for (int f = 0; f < 7; ++f) v[f] = fyz[f] + coef[f][1] * sp.delta[0][a];
        const double Wk = sp.w[0][a] * wyz;
        const double dW[3] = {dw[0][a] * dwyz[0], sp.w[0][a] * dwyz[1], sp.w[0][a] * dwyz[2]};
        out.phi[q] = v[0] * Wk;
        for (int d = 0; d < 3; ++d) out.dphi[d][q] = v[1 + d] * Wk / spacing[d] + v[0] * dW[d] - v[4 + d] * Wk;
      }
    }
  }
  return out;
}

}  // namespace systole::ibm
