#include "solver/structure/prestress.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "solver/core/errors.h"
#include "solver/geometry/topology.h"

namespace systole::structure {

std::vector<Vec3> pressure_nodal_forces(const geometry::TriMesh& mesh, const std::vector<Vec3>& x_mm,
                                        double pressure_kpa, std::uint32_t skip_region) {
  std::vector<Vec3> f(x_mm.size(), Vec3::Zero());
  const double k = pressure_kpa / 6;  // p (2 A n) / 6 = p A n / 3 per node
  for (const auto& t : mesh.tri) {
    if (skip_region != 0 && (mesh.region[t[0]] & mesh.region[t[1]] & mesh.region[t[2]] & skip_region) != 0) continue;
    const Vec3 fv = k * (x_mm[t[1]] - x_mm[t[0]]).cross(x_mm[t[2]] - x_mm[t[0]]);
    for (int c = 0; c < 3; ++c) f[t[c]] += fv;
  }
  return f;
}

namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

// One triangle's frame and gradients at the positions x: e1, e2 in-plane orthonormal, g[k] the
// gradient of the barycentric function of corner k (in-plane, 1/mm), A the area (mm^2).
struct TriangleFrame {
  Vec3 e1, e2, g[3];
  double area;
};

TriangleFrame frame_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  TriangleFrame f;
  const Vec3 cr = (b - a).cross(c - a);
  f.area = 0.5 * cr.norm();
  const Vec3 n = cr.normalized();
  f.e1 = (b - a).normalized();
  f.e2 = n.cross(f.e1);
  // grad phi_a = n x (c - b) / (2A): perpendicular to the opposite edge, towards a, |.| = 1 / h_a.
  f.g[0] = n.cross(c - b) / (2 * f.area);
  f.g[1] = n.cross(a - c) / (2 * f.area);
  f.g[2] = n.cross(b - a) / (2 * f.area);
  return f;
}

// d(g_i^T N g_j)/d(N11, N22, N12) for N = N11 e1 e1^T + N22 e2 e2^T + N12 (e1 e2^T + e2 e1^T).
std::array<double, 3> bilinear(const TriangleFrame& f, const Vec3& gi, const Vec3& gj) {
  const double i1 = gi.dot(f.e1), i2 = gi.dot(f.e2), j1 = gj.dot(f.e1), j2 = gj.dot(f.e2);
  return {i1 * j1, i2 * j2, i1 * j2 + i2 * j1};
}

// The 6 independent components (xx, yy, zz, xy, xz, yz; off-diagonals weighted sqrt 2, so the
// sum of squares is the Frobenius norm) of the 3-D tensor N as linear in (N11, N22, N12).
std::array<std::array<double, 3>, 6> tensor_components(const TriangleFrame& f) {
  static constexpr int kI[6] = {0, 1, 2, 0, 0, 1}, kJ[6] = {0, 1, 2, 1, 2, 2};
  std::array<std::array<double, 3>, 6> m{};
  for (int r = 0; r < 6; ++r) {
    const int i = kI[r], j = kJ[r];
    const double w = i == j ? 1.0 : std::sqrt(2.0);
    m[r] = {w * f.e1[i] * f.e1[j], w * f.e2[i] * f.e2[j], w * (f.e1[i] * f.e2[j] + f.e2[i] * f.e1[j])};
  }
  return m;
}

}  // namespace

Prestress membrane_prestress(const ShellModel& model, const std::vector<Vec3>& load_mn,
                             const PrestressOptions& options) {
  const std::vector<Vec3>& x = model.positions_mm();
  const geometry::TriMesh& mesh = model.stress_free_mesh();
  const std::vector<EdgeSpring>& springs = model.springs();
  const std::vector<std::uint8_t>& fixed = model.fixed();
  const std::size_t nn = x.size(), ne = springs.size(), nt = mesh.tri.size();
  if (load_mn.size() != nn)
    throw InputError("membrane_prestress: " + std::to_string(load_mn.size()) + " loads for " + std::to_string(nn) +
                     " nodes of body '" + model.name() + "'");
  if (!(options.smoothing > 0) || !(options.regularization > 0))
    throw InputError("membrane_prestress: smoothing and regularization must be > 0");
  const geometry::EdgeTopology topo(mesh);
  if (topo.edge_count() != ne)
    throw std::logic_error("membrane_prestress: the springs of body '" + model.name() + "' are not the mesh's edges");
  for (std::size_t e = 0; e < ne; ++e)
    if (topo.edge[e][0] != springs[e].i || topo.edge[e][1] != springs[e].j)
      throw std::logic_error("membrane_prestress: spring order of body '" + model.name() + "' differs from the edges'");

  // Equation rows: 3 per free node.
  std::vector<std::int32_t> row_of(nn, -1);
  Eigen::Index rows = 0;
  for (std::size_t i = 0; i < nn; ++i)
    if (!fixed[i]) row_of[i] = static_cast<std::int32_t>(3 * rows++);
  rows *= 3;
  Eigen::VectorXd rhs(rows);  // -load at the free nodes
  double load_norm2 = 0;
  for (std::size_t i = 0; i < nn; ++i)
    if (row_of[i] >= 0)
      for (int c = 0; c < 3; ++c) {
        rhs[row_of[i] + c] = -load_mn[i][c];
        load_norm2 += load_mn[i][c] * load_mn[i][c];
      }
  if (!(load_norm2 > 0)) throw InputError("membrane_prestress: body '" + model.name() + "' has no load on its free nodes");

  std::vector<Vec3> u(ne);
  std::vector<double> len(ne);
  for (std::size_t e = 0; e < ne; ++e) {
    const Vec3 d = x[springs[e].j] - x[springs[e].i];
    len[e] = d.norm();
    u[e] = d / len[e];
  }

  // M: spring forces from the triangles' stresses, F_e = sum_T -l_e A_T g_i^T N_T g_j (the edge
  // forces of a constant-stress triangle: they give its nodes exactly -A N g_k).
  std::vector<TriangleFrame> frames(nt);
  Triplets mt;
  mt.reserve(9 * nt);
  double l2_sum = 0;
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tr = mesh.tri[t];
    frames[t] = frame_of(x[tr[0]], x[tr[1]], x[tr[2]]);
    for (int k = 0; k < 3; ++k) {
      const int a = k, b = (k + 1) % 3;
      const auto e = static_cast<std::size_t>(topo.face_edge[t][k]);
      const auto co = bilinear(frames[t], frames[t].g[a], frames[t].g[b]);
      for (int c = 0; c < 3; ++c)
        mt.emplace_back(static_cast<Eigen::Index>(e), static_cast<Eigen::Index>(3 * t + c),
                        -len[e] * frames[t].area * co[c]);
      l2_sum += len[e] * len[e];
    }
  }
  Eigen::SparseMatrix<double> M(static_cast<Eigen::Index>(ne), static_cast<Eigen::Index>(3 * nt));
  M.setFromTriplets(mt.begin(), mt.end());
  // B: nodal forces of the spring forces at the free nodes.
  Triplets bt;
  bt.reserve(6 * ne);
  for (std::size_t e = 0; e < ne; ++e)
    for (int c = 0; c < 3; ++c) {
      if (row_of[springs[e].i] >= 0) bt.emplace_back(row_of[springs[e].i] + c, static_cast<Eigen::Index>(e), u[e][c]);
      if (row_of[springs[e].j] >= 0) bt.emplace_back(row_of[springs[e].j] + c, static_cast<Eigen::Index>(e), -u[e][c]);
    }
  Eigen::SparseMatrix<double> B(rows, static_cast<Eigen::Index>(ne));
  B.setFromTriplets(bt.begin(), bt.end());
  const Eigen::SparseMatrix<double> E = B * M;  // equilibrium: E N = rhs

  // S: the jump of the 3-D stress tensor across every interior edge, weighted so that the
  // smoothing is `smoothing` times the equilibrium's scale (mean l^2).
  const double ws = std::sqrt(options.smoothing * l2_sum / static_cast<double>(3 * nt));
  Triplets st;
  Eigen::Index srow = 0;
  for (std::size_t e = 0; e < ne; ++e) {
    if (topo.face_count_of(e) != 2) continue;
    const int t1 = topo.edge_face[topo.edge_face_offset[e]], t2 = topo.edge_face[topo.edge_face_offset[e] + 1];
    const auto c1 = tensor_components(frames[t1]), c2 = tensor_components(frames[t2]);
    for (int r = 0; r < 6; ++r, ++srow)
      for (int c = 0; c < 3; ++c) {
        st.emplace_back(srow, 3 * t1 + c, ws * c1[r][c]);
        st.emplace_back(srow, 3 * t2 + c, -ws * c2[r][c]);
      }
  }
  Eigen::SparseMatrix<double> S(srow, static_cast<Eigen::Index>(3 * nt));
  S.setFromTriplets(st.begin(), st.end());

  Eigen::SparseMatrix<double> K = Eigen::SparseMatrix<double>(E.transpose() * E) + Eigen::SparseMatrix<double>(S.transpose() * S);
  double diag = 0;
  for (Eigen::Index k = 0; k < K.rows(); ++k) diag += K.coeff(k, k);
  const double mu = options.regularization * diag / static_cast<double>(K.rows());
  for (Eigen::Index k = 0; k < K.rows(); ++k) K.coeffRef(k, k) += mu;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(K);
  if (ldlt.info() != Eigen::Success)
    throw std::runtime_error("membrane_prestress: the normal equations of body '" + model.name() + "' did not factorise");
  const Eigen::VectorXd Etr = E.transpose() * rhs;
  Eigen::VectorXd N = ldlt.solve(Etr);
  for (int it = 0; it < 3; ++it) N += ldlt.solve(Etr - K * N);  // iterative refinement
  const Eigen::VectorXd force = M * N;

  Prestress out;
  out.membrane_tension_mn_per_mm.resize(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    // The larger principal tension of the triangle's 2 x 2 stress.
    const double a = N[3 * t], b = N[3 * t + 1], c = N[3 * t + 2];
    out.membrane_tension_mn_per_mm[t] = 0.5 * (a + b) + std::sqrt(0.25 * (a - b) * (a - b) + c * c);
  }

  // Rest lengths by inverting the law: tau(eps) C / l = F (eps < 0 for a compressive force).
  const ShellOptions& so = model.options();
  const LawParams lp{so.fung_exponent_cap, so.fung_compression_fraction};
  const SpringLaw& law = model.law();
  std::vector<double> tau_needed(ne, 0.0);
  int beyond = 0;
  std::size_t worst = ne;
  double worst_ratio = 0;
  for (std::size_t e = 0; e < ne; ++e) {
    const EdgeSpring& s = springs[e];
    tau_needed[e] = force[static_cast<Eigen::Index>(e)] * len[e] / s.cross_section_mm3;
    if (!options.compression && tau_needed[e] < 0) tau_needed[e] = 0;
    if (tau_needed[e] == 0) continue;
    const double ratio = tau_needed[e] / law.stress(std::copysign(so.strain_limit, tau_needed[e]), s.c_kpa, s.alpha, lp);
    if (ratio >= 1) ++beyond;
    if (ratio > worst_ratio) {
      worst_ratio = ratio;
      worst = e;
    }
  }
  if (beyond > 0) {
    const EdgeSpring& s = springs[worst];
    std::ostringstream m;
    m << "body '" << model.name() << "': the pre-stress needs " << beyond << " of " << ne
      << " springs beyond their stress at the strain limit " << so.strain_limit << "; the worst, spring " << s.i << "-"
      << s.j << " (at " << x[s.i].transpose() << " mm), " << tau_needed[worst] << " kPa, " << worst_ratio
      << " times what it carries there (c = " << s.c_kpa << " kPa): the load is too large for this tissue";
    throw InputError(m.str());
  }
  out.rest_length_mm.resize(ne);
  out.force_mn.assign(ne, 0.0);
  double strain_sum = 0;
  int stressed = 0;
  for (std::size_t e = 0; e < ne; ++e) {
    const EdgeSpring& s = springs[e];
    if (tau_needed[e] == 0) {
      out.rest_length_mm[e] = len[e];
      ++out.slack_springs;
      continue;
    }
    if (tau_needed[e] < 0) ++out.compressed_springs;
    // Bisection on [0, 1) ([-1, 0]), not on the strain limit's bracket: the check above puts
    // the root inside the limit, and the rest lengths do not depend on the limit (a guard; a run
    // stopped by it resumes from its checkpoint with a looser one, fsei/checkpoint.h).
    double lo = tau_needed[e] > 0 ? 0 : -1, hi = tau_needed[e] > 0 ? 1 : 0;
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
      const double mid = 0.5 * (lo + hi);
      (law.stress(mid, s.c_kpa, s.alpha, lp) < tau_needed[e] ? lo : hi) = mid;
    }
    const double eps = 0.5 * (lo + hi);
    out.rest_length_mm[e] = len[e] * (1 - eps);
    out.force_mn[e] = law.stress(eps, s.c_kpa, s.alpha, lp) * s.cross_section_mm3 / len[e];
    strain_sum += eps;
    ++stressed;
    out.min_strain = std::min(out.min_strain, eps);
    if (eps > out.max_strain) {
      out.max_strain = eps;
      out.max_strain_spring = static_cast<std::int32_t>(e);
    }
  }
  out.mean_strain = stressed > 0 ? strain_sum / stressed : 0;

  // The residual the pre-stressed model sees at x.
  std::vector<Vec3> r(load_mn);
  for (std::size_t e = 0; e < ne; ++e) {
    r[springs[e].i] += out.force_mn[e] * u[e];
    r[springs[e].j] -= out.force_mn[e] * u[e];
  }
  double r2 = 0;
  for (std::size_t i = 0; i < nn; ++i)
    if (!fixed[i]) r2 += r[i].squaredNorm();
  out.residual_relative = std::sqrt(r2 / load_norm2);
  return out;
}

}  // namespace systole::structure
