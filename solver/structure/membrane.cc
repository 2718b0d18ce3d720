// ShellModel's constant-strain membrane triangles (ShellOptions::membrane = "triangles", ours):
// eq 16's Fung energy per triangle, in eq 17's strain measure along the triangle's fibre and
// cross-fibre directions, instead of one spring per edge (docs/structure.md, "The membrane
// element").
//
// Per triangle with stress-free area A0, thickness s, fibre frame (f0, c0) in its plane and
// shape-function gradients g_k (2-vectors in that frame): F = sum_k x_k g_k^T (3 x 2); the
// deformed fibre and cross-fibre vectors a = F f0, b = F c0; the stretches lambda_f = |a|,
// lambda_c = |b|; eq 17's strains eps = 1 - 1/lambda (= (l - l0)/l); the shear
// gamma = (a . b) / |a x b| (the cotangent of the deformed angle between them, 0 at rest);
//   Q = alpha_f eps_f^2 + alpha_c eps_c^2 + alpha_c gamma^2 / 2,   W = s A0 (c/2)(e^Q - 1).
// eps -> -inf as lambda -> 0 and gamma -> +-inf as the angle closes, so, like eq 17, the energy
// resists a triangle's collapse without bound. (A Green-strain form, E = (F^T F - I)/2, was
// tried first and refused: its energy stays finite as a triangle collapses, so the LV's wall
// crumpled at 2-8 ms, docs/notes/tissue-notebook.md.) The shear term is absent from eq 16 (ours):
// without it the element has a zero-energy shear mode; at small strain Q is then
// alpha_f E_ff^2 + alpha_c E_cc^2 + 2 alpha_c E_fc^2, isotropic when alpha_f = alpha_c.
// A triangle without a fibre is isotropic with alpha = sqrt((alpha_f^2 + alpha_c^2)/2), the
// springs' convention for cos^2 phi = 1/2.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "solver/core/errors.h"
#include "solver/structure/shell.h"

namespace systole::structure {
namespace {

using Mat32 = Eigen::Matrix<double, 3, 2>;

Mat32 deformation_gradient(const std::vector<Vec3>& x, const std::int32_t node[3], const double g[3][2]) {
  Mat32 F = Mat32::Zero();
  for (int k = 0; k < 3; ++k) {
    F.col(0) += g[k][0] * x[node[k]];
    F.col(1) += g[k][1] * x[node[k]];
  }
  return F;
}

// True when the triangle's deformed fibre and cross-fibre vectors span a plane (it has not
// collapsed to a segment or a point); the energy is unbounded there, so a state reaching it is a
// failure, not a value.
bool spans_plane(const Mat32& F) {
  const Vec3 a = F.col(0), b = F.col(1);
  return a.cross(b).norm() > 1e-12 * a.norm() * b.norm() && a.norm() > 0 && b.norm() > 0;
}

// Q and its gradients dQ/da, dQ/db / 2 (so that dW/da = s A0 c e^Q qa), and what the stable
// step's bound needs.
struct FungState {
  double q;
  Vec3 qa, qb;
  double lam_min, eps_max, gamma, grad_gamma;  // min stretch, max |eps|, gamma, |d gamma / d(a, b)|
};
FungState fung_state(const Mat32& F, double af, double ac) {
  const Vec3 a = F.col(0), b = F.col(1);
  const double la = a.norm(), lb = b.norm();
  const double ea = 1 - 1 / la, eb = 1 - 1 / lb;
  const Vec3 n = a.cross(b);
  const double nn = n.norm(), d = a.dot(b), gamma = d / nn;
  const Vec3 ga = b / nn - (d / (nn * nn * nn)) * b.cross(n);  // d gamma / da
  const Vec3 gb = a / nn - (d / (nn * nn * nn)) * n.cross(a);  // d gamma / db
  FungState st;
  st.q = af * ea * ea + ac * eb * eb + 0.5 * ac * gamma * gamma;
  // dQ/da / 2 = alpha_f eps_f (d eps / d lambda) a / lambda + alpha_c gamma / 2 d gamma / da
  st.qa = (af * ea / (la * la * la)) * a + (0.5 * ac * gamma) * ga;
  st.qb = (ac * eb / (lb * lb * lb)) * b + (0.5 * ac * gamma) * gb;
  st.lam_min = std::min(la, lb);
  st.eps_max = std::max(std::abs(ea), std::abs(eb));
  st.gamma = gamma;
  st.grad_gamma = std::max(ga.norm(), gb.norm());
  return st;
}

}  // namespace

void ShellModel::build_membrane(const ShellMaterials& materials) {
  membrane_.reserve(mesh_.triangle_count());
  for (std::size_t t = 0; t < mesh_.triangle_count(); ++t) {
    const auto& tr = mesh_.tri[t];
    const Vec3 e1 = mesh_.position_mm[tr[1]] - mesh_.position_mm[tr[0]];
    const Vec3 e2 = mesh_.position_mm[tr[2]] - mesh_.position_mm[tr[0]];
    const Vec3 n = e1.cross(e2).normalized();
    const TissueMaterial& m = materials.tissue[static_cast<int>(mesh_.tissue[t])];
    MembraneTriangle mt{};
    mt.c_kpa = m.c_kpa;
    Vec3 f0 = mesh_.fibre[t] - mesh_.fibre[t].dot(n) * n;
    if (f0.norm() > 1e-12 * mesh_.fibre[t].norm() && mesh_.fibre[t].norm() > 0) {
      f0.normalize();
      mt.alpha_f = m.alpha_f;
      mt.alpha_c = m.alpha_c;
    } else {  // no fibre: isotropic (any in-plane frame)
      f0 = e1.normalized();
      mt.alpha_f = mt.alpha_c = std::sqrt(0.5 * (m.alpha_f * m.alpha_f + m.alpha_c * m.alpha_c));
    }
    const Vec3 c0 = n.cross(f0);
    Eigen::Matrix2d D;  // columns: the reference edges e1, e2 in the (f0, c0) frame
    D << e1.dot(f0), e2.dot(f0), e1.dot(c0), e2.dot(c0);
    const Eigen::Matrix2d Dinv = D.inverse();  // g_1 = row 0 of D^-1, g_2 = row 1, g_0 = -g_1 - g_2
    for (int j = 0; j < 2; ++j) {
      mt.g[1][j] = Dinv(0, j);
      mt.g[2][j] = Dinv(1, j);
      mt.g[0][j] = -Dinv(0, j) - Dinv(1, j);
    }
    for (int k = 0; k < 3; ++k) mt.node[k] = tr[k];
    mt.volume_mm3 = mesh_.thickness_mm[t] * mesh_.area_mm2(t);
    membrane_.push_back(mt);
  }
}

// Gershgorin rows (row != nullptr, ours, approximate like the springs' and hinges'): with
// W = s A0 (c/2) e^Q, each stretch term adds c e^Q alpha [(1 + 2Q)/lambda^4 + 3 |eps| / lambda^3]
// (its axial curvature and the transverse rate dW/dlambda / lambda) and the shear term
// c e^Q alpha_c (1 + 2Q) |d gamma|^2 (1 + |gamma|) (the curvature of gamma^2 / 2 taken as
// |d gamma|^2 (1 + |gamma|)); a node's row gets twice their sum times sqrt(3) |g_k| sum_l |g_l|.
void ShellModel::throw_collapsed_triangle(const MembraneTriangle& t, const std::vector<Vec3>& x) const {
  std::ostringstream what;
  what << "membrane triangle (nodes " << t.node[0] << ", " << t.node[1] << ", " << t.node[2]
       << ") collapsed: its deformed fibre and cross-fibre directions no longer span a plane, or its energy "
          "overflowed (at ("
       << x[t.node[0]].x() << ", " << x[t.node[0]].y() << ", " << x[t.node[0]].z() << ") mm)";
  throw_instability(t.node[0], what.str());
}

void ShellModel::add_membrane_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f, double* row) const {
  for (const MembraneTriangle& t : membrane_) {
    const Mat32 F = deformation_gradient(x, t.node, t.g);
    if (!spans_plane(F)) throw_collapsed_triangle(t, x);
    const FungState st = fung_state(F, t.alpha_f, t.alpha_c);
    const double vce = t.volume_mm3 * t.c_kpa * std::exp(st.q);  // dW/dQ = vce / 2
    if (!std::isfinite(vce)) throw_collapsed_triangle(t, x);
    for (int k = 0; k < 3; ++k) f[t.node[k]] -= vce * (st.qa * t.g[k][0] + st.qb * t.g[k][1]);
    if (row == nullptr) continue;
    const double l2 = st.lam_min * st.lam_min, amax = std::max(t.alpha_f, t.alpha_c);
    const double stretch = amax * ((1 + 2 * st.q) / (l2 * l2) + 3 * st.eps_max / (l2 * st.lam_min));
    const double shear = t.alpha_c * (1 + 2 * st.q) * st.grad_gamma * st.grad_gamma * (1 + std::abs(st.gamma));
    const double k_e = vce * 2 * (stretch + shear);
    double gn[3], sum = 0;
    for (int k = 0; k < 3; ++k) sum += (gn[k] = std::hypot(t.g[k][0], t.g[k][1]));
    for (int k = 0; k < 3; ++k) row[t.node[k]] += std::sqrt(3.0) * k_e * gn[k] * sum;
  }
}

double ShellModel::membrane_energy(const std::vector<Vec3>& x) const {
  double w = 0;
  for (const MembraneTriangle& t : membrane_) {
    const Mat32 F = deformation_gradient(x, t.node, t.g);
    if (!spans_plane(F)) return std::numeric_limits<double>::infinity();
    const FungState st = fung_state(F, t.alpha_f, t.alpha_c);
    w += t.volume_mm3 * 0.5 * t.c_kpa * std::expm1(st.q);
  }
  return w;
}

}  // namespace systole::structure
