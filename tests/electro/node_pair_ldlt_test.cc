// NodePairLdlt (solver/electro/node_pair_ldlt.h): the bidomain block system solved as before
// (Eigen SimplicialLDLT with AMD on the 2n unknowns, the reference kept here and behind
// TissueOptions::reference_block_solver) and by the node-pair solver agree to round-off, for
// one solve and over a whole upstroke of the tissue solver.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <Eigen/SparseCholesky>

#include "solver/core/errors.h"
#include "solver/electro/fem.h"
#include "solver/electro/node_pair_ldlt.h"
#include "solver/electro/tissue.h"

namespace systole::electro {
namespace {

// Two sheets 5 mm apart (two connected components, so two pinned u_e), fibres at 30 degrees.
ElectroMesh two_sheets() {
  ElectroMesh m = make_sheet(6.0, 3.0, 0.25, 30.0);
  const ElectroMesh b = make_sheet(4.0, 3.0, 0.25, -20.0);
  const auto offset = static_cast<std::int32_t>(m.position_mm.size());
  for (const Vec3& p : b.position_mm) m.position_mm.push_back(p + Vec3(0, 0, 5));
  for (auto c : b.cell) {
    for (auto& v : c)
      if (v >= 0) v += offset;
    m.cell.push_back(c);
  }
  m.fibre.insert(m.fibre.end(), b.fibre.begin(), b.fibre.end());
  m.node_region.insert(m.node_region.end(), b.node_region.begin(), b.node_region.end());
  m.node_domain.insert(m.node_domain.end(), b.node_domain.begin(), b.node_domain.end());
  return m;
}

// The bidomain block matrix of tissue.cc (backward Euler over dt_ms, theta = 1):
// [[c M / dt + K_i, K_i], [K_i, K_i + K_e]] with u_e pinned (identity row and column) at the
// first node of every connected component — the former code, kept as the reference.
SparseMatrix reference_block(const ElectroMesh& mesh, double dt_ms) {
  const double c = 1400.0 * 1.0;
  const SparseMatrix mass = assemble_mass(mesh);
  const SparseMatrix k_i = assemble_stiffness(mesh, {7.0, 0.8});
  const SparseMatrix k_sum = SparseMatrix(k_i + assemble_stiffness(mesh, {25.0, 9.5}));
  const SparseMatrix a = SparseMatrix(mass * (c / dt_ms)) + k_i;
  const auto n = static_cast<Eigen::Index>(mesh.node_count());
  const std::vector<std::int32_t> comp = mesh.components();
  std::vector<char> pinned(static_cast<std::size_t>(2 * n), 0), seen;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(comp[static_cast<std::size_t>(i)]);
    if (k >= seen.size()) seen.resize(k + 1, 0);
    if (!seen[k]) seen[k] = 1, pinned[static_cast<std::size_t>(n + i)] = 1;
  }
  std::vector<Eigen::Triplet<double>> t;
  auto add = [&](const SparseMatrix& m, Eigen::Index r0, Eigen::Index c0, bool transpose) {
    for (Eigen::Index k = 0; k < m.outerSize(); ++k)
      for (SparseMatrix::InnerIterator it(m, k); it; ++it) {
        Eigen::Index r = it.row() + r0, col = it.col() + c0;
        if (transpose) std::swap(r, col);
        if (pinned[static_cast<std::size_t>(r)] || pinned[static_cast<std::size_t>(col)]) continue;
        t.emplace_back(r, col, it.value());
      }
  };
  add(a, 0, 0, false);
  add(k_i, 0, n, false);
  add(k_i, 0, n, true);
  add(k_sum, n, n, false);
  for (Eigen::Index i = 0; i < 2 * n; ++i)
    if (pinned[static_cast<std::size_t>(i)]) t.emplace_back(i, i, 1.0);
  SparseMatrix out(2 * n, 2 * n);
  out.setFromTriplets(t.begin(), t.end());
  return out;
}

TEST(NodePairLdlt, OneSolveEqualsSimplicialLdltToRoundOff) {
  const ElectroMesh mesh = two_sheets();
  const std::vector<std::int32_t> comp = mesh.components();
  ASSERT_EQ(*std::max_element(comp.begin(), comp.end()), 1);
  for (double dt_ms : {0.05, 0.01}) {
    const SparseMatrix a = reference_block(mesh, dt_ms);
    const Eigen::SimplicialLDLT<SparseMatrix> reference(a);
    ASSERT_EQ(reference.info(), Eigen::Success);
    const NodePairLdlt solver(a, "test");
    EXPECT_EQ(solver.nodes(), mesh.node_count());
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-100.0, 100.0);
    Eigen::VectorXd b(a.rows()), x;
    for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = u(rng);
    solver.solve(b, x);
    const Eigen::VectorXd x_ref = reference.solve(b);
    const double diff = (x - x_ref).cwiseAbs().maxCoeff(), scale = x_ref.cwiseAbs().maxCoeff();
    const double residual = (a * x - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
    const double residual_ref = (a * x_ref - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
    std::printf("dt %.2f ms: max |x - x_ref| / max |x_ref| = %.2e, relative residual %.2e (reference %.2e)\n",
                dt_ms, diff / scale, residual, residual_ref);
    EXPECT_LT(diff, 1e-12 * scale);
    EXPECT_LT(residual, 1e-12);
  }
}

TEST(NodePairLdlt, RejectsOddSizeAndSingularMatrices) {
  SparseMatrix odd(3, 3);
  odd.setIdentity();
  EXPECT_THROW(NodePairLdlt(odd, "odd"), InstabilityError);
  SparseMatrix singular(4, 4);  // zero pivot
  singular.insert(0, 0) = 1.0;
  singular.insert(2, 2) = 1.0;
  singular.insert(3, 3) = 1.0;
  EXPECT_THROW(NodePairLdlt(singular, "singular"), InstabilityError);
}

TissueOptions bidomain_options(Splitting s) {
  TissueOptions o;
  o.formulation = Formulation::kBidomain;
  o.splitting = s;
  o.dt_ms = 0.02;
  o.chi_per_cm = 1400.0;
  o.cm_uf_per_cm2 = 1.0;
  o.sigma_i = {7.0, 0.8};
  o.sigma_e = {25.0, 9.5};
  o.domain_cell_models = {"ttp06_epi"};
  o.activation_threshold_mv = -40.0;
  o.tension_k_kpa = 50.0;
  StimulusSpec st;
  st.name = "box";
  st.region.kind = StimulusRegion::Kind::kBox;
  st.region.box_min_mm = Vec3(-1, -1, -1);
  st.region.box_max_mm = Vec3(1.0, 100, 100);
  st.amplitude_ua_per_cm2 = 100.0;
  st.duration_ms = 2.0;
  st.start_ms = 0.0;
  st.period_ms = 0.0;
  o.stimuli = {st};
  return o;
}

// Every step of an upstroke crossing both sheets: Vm, u_e and activation times of the
// node-pair solver against the reference block solve.
TEST(NodePairLdlt, TissueSolverMatchesTheReferenceBlockSolve) {
  const ElectroMesh mesh = two_sheets();
  for (Splitting sp : {Splitting::kGodunov, Splitting::kStrang}) {
    TissueOptions o = bidomain_options(sp);
    TissueSolver fast(mesh, o);
    o.reference_block_solver = true;
    TissueSolver reference(mesh, o);
    double dv = 0, due = 0, dact = 0, vmax = 0;
    for (int n = 0; n < 500; ++n) {  // 10 ms
      fast.step();
      reference.step();
      for (std::size_t i = 0; i < mesh.node_count(); ++i) {
        dv = std::max(dv, std::abs(fast.vm_mv()[i] - reference.vm_mv()[i]));
        due = std::max(due, std::abs(fast.ue_mv()[i] - reference.ue_mv()[i]));
        vmax = std::max(vmax, std::abs(reference.vm_mv()[i]));
      }
    }
    int activated = 0;
    for (std::size_t i = 0; i < mesh.node_count(); ++i) {
      const double a = fast.activation().activation_ms()[i], b = reference.activation().activation_ms()[i];
      ASSERT_EQ(std::isnan(a), std::isnan(b));
      if (!std::isnan(a)) ++activated, dact = std::max(dact, std::abs(a - b));
    }
    std::printf("%s, 10 ms: max |dVm| %.2e mV, max |du_e| %.2e mV, max |d activation| %.2e ms (%d of %zu nodes active)\n",
                sp == Splitting::kGodunov ? "godunov" : "strang", dv, due, dact, activated, mesh.node_count());
    EXPECT_GT(activated, static_cast<int>(mesh.node_count() / 2));
    EXPECT_LT(dv, 1e-9 * vmax);
    EXPECT_LT(due, 1e-9 * vmax);
    EXPECT_LT(dact, 1e-9);
  }
}

}  // namespace
}  // namespace systole::electro
