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
// stencils. delta[k][d] = (x_k,d − X_d)/Δ_d (cells), valid[k] = node inside the fluid.
struct Support {
  MlsStencil s;
  std::array<std::array<double, 3>, 27> delta{};
  std::array<bool, 27> valid{};
  std::array<double, 27> weight{};
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  Eigen::Matrix4d A_inverse;
};

int wrap(int i, int n) { return ((i % n) + n) % n; }

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
  const int k_lo = L == Location::z_face ? 1 : 0, k_hi = L == Location::z_face ? g.nz() - 1 : g.nz() - 1;
  for (int c = 0; c < 3; ++c)
    for (int b = 0; b < 3; ++b)
      for (int a = 0; a < 3; ++a) {
        const int q = a + 3 * b + 9 * c;
        const int idx[3] = {centre[0] - 1 + a, centre[1] - 1 + b, centre[2] - 1 + c};
        double w = 1;
        for (int d = 0; d < 3; ++d) {
          sp.delta[q][d] = (idx[d] + dim[d].offset) - X[d] / dim[d].spacing;
          w *= mls_weight(std::abs(sp.delta[q][d]) / kMlsRadiusCells);
        }
        const int k = idx[2];
        sp.valid[q] = k >= k_lo && k <= k_hi;
        sp.weight[q] = sp.valid[q] ? w : 0.0;
        if (!sp.valid[q]) continue;
        const Eigen::Vector4d p(1, sp.delta[q][0], sp.delta[q][1], sp.delta[q][2]);
        sp.A += w * p * p.transpose();
      }
  bool invertible = false;
  sp.A.computeInverseWithCheck(sp.A_inverse, invertible, 1e-12);
  if (!invertible)
    throw std::logic_error("ibm MLS: singular moment matrix at (" + std::to_string(X[0]) + ", " + std::to_string(X[1]) +
                           ", " + std::to_string(X[2]) + "): the point is too close to a wall");
  return sp;
}

}  // namespace

MlsStencil mls_stencil(const grid::Grid& g, grid::Location L, const Eigen::Vector3d& X) {
  Support sp = build_support(g, L, X);
  const Eigen::Vector4d c = sp.A_inverse.row(0).transpose();
  for (int q = 0; q < 27; ++q) {
    if (!sp.valid[q]) continue;
    sp.s.phi[q] = (c[0] + c[1] * sp.delta[q][0] + c[2] * sp.delta[q][1] + c[3] * sp.delta[q][2]) * sp.weight[q];
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
  // ∂W_k/∂X_d and ∂A/∂X_d.
  std::array<std::array<double, 3>, 27> dW{};
  Eigen::Matrix4d dA[3] = {Eigen::Matrix4d::Zero(), Eigen::Matrix4d::Zero(), Eigen::Matrix4d::Zero()};
  for (int q = 0; q < 27; ++q) {
    if (!sp.valid[q]) continue;
    double w[3], dw[3];
    for (int d = 0; d < 3; ++d) {
      const double r = std::abs(sp.delta[q][d]) / kMlsRadiusCells;
      w[d] = mls_weight(r);
      // r = |x_k − X|/(2Δ): ∂r/∂X_d = −sign(x_k − X)/(2Δ_d)
      const double sign = sp.delta[q][d] > 0 ? 1.0 : (sp.delta[q][d] < 0 ? -1.0 : 0.0);
      dw[d] = mls_weight_derivative(r) * (-sign / (kMlsRadiusCells * spacing[d]));
    }
    const Eigen::Vector4d p(1, sp.delta[q][0], sp.delta[q][1], sp.delta[q][2]);
    for (int d = 0; d < 3; ++d) {
      dW[q][d] = dw[d] * w[(d + 1) % 3] * w[(d + 2) % 3];
      dA[d] += dW[q][d] * p * p.transpose();
    }
  }
  Eigen::RowVector4d cdA_Ai[3];
  for (int d = 0; d < 3; ++d) cdA_Ai[d] = c.transpose() * dA[d] * Ai;
  for (int q = 0; q < 27; ++q) {
    out.phi[q] = sp.s.phi[q];
    if (!sp.valid[q]) continue;
    const Eigen::Vector4d p(1, sp.delta[q][0], sp.delta[q][1], sp.delta[q][2]);
    const double Wk = sp.weight[q];
    for (int d = 0; d < 3; ++d) {
      // ∂φ/∂X_d = (A⁻¹e_{d+1})·p_k W_k/Δ_d + (c·p_k) ∂W_k − c ∂A A⁻¹ p_k W_k
      out.dphi[d][q] = Ai.col(d + 1).dot(p) * Wk / spacing[d] + c.dot(p) * dW[q][d] - cdA_Ai[d].dot(p) * Wk;
    }
  }
  return out;
}

}  // namespace systole::ibm
