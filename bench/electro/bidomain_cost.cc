// The bidomain diffusion cost on the default left heart (scene "electro", docs/electro.md
// "Costs", issue #8):
//  1. fill and CPU ms per solve: monodomain SimplicialLDLT, the bidomain block system by
//     SimplicialLDLT (AMD on 2n unknowns, the former solver) and by NodePairLdlt (current);
//  2. "beat": one default beat (17 143 steps) by the current solver and the reference
//     (TissueOptions::reference_block_solver) in lockstep: CPU seconds of reaction and
//     diffusion (calling thread), max |dVm| and |du_e| over all nodes and steps, activation
//     time and APD90 differences.
// CPU time throughout (the machine is shared). Usage: electro_bidomain_cost [beat]
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <Eigen/SparseCholesky>

#include "solver/config/scenario.h"
#include "solver/electro/fem.h"
#include "solver/electro/node_pair_ldlt.h"
#include "solver/electro/tissue.h"
#include "solver/geometry/left_heart.h"
#include "solver/scene/left_heart_ep.h"

using namespace systole;
using namespace systole::electro;

static double cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// CPU ms per solve of a solver with solve(b) -> x (b perturbed between repetitions).
template <class F>
static double ms_per_solve(Eigen::Index size, F&& solve) {
  Eigen::VectorXd b = Eigen::VectorXd::Random(size), x;
  const int reps = 500;
  const double t0 = cpu_s();
  for (int r = 0; r < reps; ++r) {
    solve(b, x);
    b[0] += 1e-9 * x[1];
  }
  return 1e3 * (cpu_s() - t0) / reps;
}

static void solve_costs(const ElectroMesh& mesh, const TissueOptions& o) {
  const auto n = static_cast<Eigen::Index>(mesh.node_count());
  std::vector<double> cell_scale(mesh.cell_count());
  for (std::size_t c = 0; c < mesh.cell_count(); ++c)
    cell_scale[c] = o.domain_conductivity_scale[mesh.node_domain[static_cast<std::size_t>(mesh.cell[c][0])]];
  const double c = o.chi_per_cm * o.cm_uf_per_cm2 / o.dt_ms;
  const SparseMatrix mass = assemble_mass(mesh);
  const SparseMatrix k_i = assemble_stiffness(mesh, o.sigma_i, cell_scale);
  const SparseMatrix k_sum = SparseMatrix(k_i + assemble_stiffness(mesh, o.sigma_e, cell_scale));
  const SparseMatrix k_mono = assemble_stiffness(mesh, monodomain_conductivity(o.sigma_i, o.sigma_e), cell_scale);
  const SparseMatrix a = SparseMatrix(mass * c) + k_i;
  // The block system with u_e pinned at the first node of each component (tissue.cc).
  const std::vector<std::int32_t> comp = mesh.components();
  std::vector<char> pinned(static_cast<std::size_t>(n), 0), seen;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(comp[static_cast<std::size_t>(i)]);
    if (k >= seen.size()) seen.resize(k + 1, 0);
    if (!seen[k]) seen[k] = 1, pinned[static_cast<std::size_t>(i)] = 1;
  }
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index col = 0; col < n; ++col) {
    for (SparseMatrix::InnerIterator it(a, col); it; ++it) t.emplace_back(it.row(), it.col(), it.value());
    for (SparseMatrix::InnerIterator it(k_i, col); it; ++it)
      if (!pinned[static_cast<std::size_t>(it.col())]) {
        t.emplace_back(it.row(), n + it.col(), it.value());
        t.emplace_back(n + it.col(), it.row(), it.value());
      }
    for (SparseMatrix::InnerIterator it(k_sum, col); it; ++it)
      if (!pinned[static_cast<std::size_t>(it.row())] && !pinned[static_cast<std::size_t>(it.col())])
        t.emplace_back(n + it.row(), n + it.col(), it.value());
  }
  for (Eigen::Index i = 0; i < n; ++i)
    if (pinned[static_cast<std::size_t>(i)]) t.emplace_back(n + i, n + i, 1.0);
  SparseMatrix block(2 * n, 2 * n);
  block.setFromTriplets(t.begin(), t.end());

  const SparseMatrix mono_a = SparseMatrix(mass * c) + k_mono;
  const Eigen::SimplicialLDLT<SparseMatrix> mono(mono_a);
  double t0 = cpu_s();
  const Eigen::SimplicialLDLT<SparseMatrix> reference(block);
  const double setup_ref = cpu_s() - t0;
  t0 = cpu_s();
  const NodePairLdlt node_pair(block, "bench");
  const double setup_np = cpu_s() - t0;
  std::printf("default heart: %ld nodes, dt %.3f ms, %zu components\n\n", static_cast<long>(n), o.dt_ms, seen.size());
  std::printf("| solver | unknowns | entries of L | setup (CPU s) | solve (CPU ms) |\n|---|---|---|---|---|\n");
  std::printf("| monodomain, SimplicialLDLT (AMD) | %ld | %ld | - | %.3f |\n", static_cast<long>(n),
              static_cast<long>(mono.matrixL().nestedExpression().nonZeros()),
              ms_per_solve(n, [&](const Eigen::VectorXd& b, Eigen::VectorXd& x) { x = mono.solve(b); }));
  std::printf("| bidomain, SimplicialLDLT (AMD on 2n, before) | %ld | %ld | %.3f | %.3f |\n", static_cast<long>(2 * n),
              static_cast<long>(reference.matrixL().nestedExpression().nonZeros()), setup_ref,
              ms_per_solve(2 * n, [&](const Eigen::VectorXd& b, Eigen::VectorXd& x) { x = reference.solve(b); }));
  std::printf("| bidomain, NodePairLdlt (node AMD, 2x2 blocks, now) | %ld | %zu | %.3f | %.3f |\n", static_cast<long>(2 * n),
              node_pair.factor_entries(), setup_np,
              ms_per_solve(2 * n, [&](const Eigen::VectorXd& b, Eigen::VectorXd& x) { node_pair.solve(b, x); }));
  Eigen::VectorXd b = Eigen::VectorXd::Random(2 * n), x;
  node_pair.solve(b, x);
  const Eigen::VectorXd x_ref = reference.solve(b);
  std::printf("\none solve, random rhs: max |x - x_ref| / max |x_ref| = %.2e\n",
              (x - x_ref).cwiseAbs().maxCoeff() / x_ref.cwiseAbs().maxCoeff());
}

// One solver alone over the beat (its factor alone in the cache): CPU seconds per stage.
static void alone(const ElectroMesh& mesh, TissueOptions o, long steps, bool reference) {
  o.reference_block_solver = reference;
  TissueSolver s(mesh, o);
  const double t0 = cpu_s();
  for (long k = 0; k < steps; ++k) s.step();
  const double total = cpu_s() - t0;
  std::printf("| %s, alone | %.2f | %.2f | %.3f | %.2f |\n", reference ? "before (SimplicialLDLT)" : "now (NodePairLdlt)",
              s.reaction_cpu_seconds(), s.diffusion_cpu_seconds(), 1e3 * s.diffusion_cpu_seconds() / static_cast<double>(steps),
              total);
}

static void beat(const ElectroMesh& mesh, TissueOptions o, long steps) {
  std::printf("\none beat, %ld steps (%.1f ms), each solver alone:\n\n| solver | reaction (CPU s) | diffusion (CPU s) | "
              "diffusion (CPU ms / step) | step() total (CPU s) |\n|---|---|---|---|---|\n", steps, steps * o.dt_ms);
  alone(mesh, o, steps, true);
  alone(mesh, o, steps, false);
  TissueSolver now(mesh, o);
  o.reference_block_solver = true;
  TissueSolver before(mesh, o);
  double dv = 0, due = 0;
  for (long k = 0; k < steps; ++k) {
    now.step();
    before.step();
    for (std::size_t i = 0; i < mesh.node_count(); ++i) {
      dv = std::max(dv, std::abs(now.vm_mv()[i] - before.vm_mv()[i]));
      due = std::max(due, std::abs(now.ue_mv()[i] - before.ue_mv()[i]));
    }
  }
  const std::vector<double> apd_now = now.activation().apd_ms(), apd_before = before.activation().apd_ms();
  double dact = 0, dapd = 0;
  std::size_t active = 0, mismatch = 0;
  for (std::size_t i = 0; i < mesh.node_count(); ++i) {
    const double a = now.activation().activation_ms()[i], b = before.activation().activation_ms()[i];
    if (std::isnan(a) != std::isnan(b) || std::isnan(apd_now[i]) != std::isnan(apd_before[i])) ++mismatch;
    if (!std::isnan(a) && !std::isnan(b)) ++active, dact = std::max(dact, std::abs(a - b));
    if (!std::isnan(apd_now[i]) && !std::isnan(apd_before[i])) dapd = std::max(dapd, std::abs(apd_now[i] - apd_before[i]));
  }
  std::printf("\nthe same beat, both solvers in lockstep (their factors compete for the cache):\n\n| solver | reaction (CPU s) | diffusion (CPU s) | diffusion (CPU ms / step) |\n|---|---|---|---|\n");
  std::printf("| before (SimplicialLDLT) | %.2f | %.2f | %.3f |\n", before.reaction_cpu_seconds(), before.diffusion_cpu_seconds(),
              1e3 * before.diffusion_cpu_seconds() / static_cast<double>(steps));
  std::printf("| now (NodePairLdlt) | %.2f | %.2f | %.3f |\n", now.reaction_cpu_seconds(), now.diffusion_cpu_seconds(),
              1e3 * now.diffusion_cpu_seconds() / static_cast<double>(steps));
  std::printf("\nagreement over the beat: max |dVm| %.3e mV, max |du_e| %.3e mV (all nodes, all steps); "
              "max |d activation| %.3e ms (%zu nodes activated), max |d APD90| %.3e ms; NaN pattern mismatches %zu\n",
              dv, due, dact, active, dapd, mismatch);
}

int main(int argc, char** argv) {
  const config::Scenario s = config::parse_scenario({{"scene", "electro"}, {"beats", 1}});
  const geometry::LeftHeart lh = geometry::build_left_heart(s.geometry, s.fluid);
  const scene::LeftHeartEp ep = scene::left_heart_ep(s, lh.body(geometry::kLvBody), lh.body(geometry::kLaBody));
  solve_costs(ep.mesh, ep.options);
  if (argc > 1 && std::strcmp(argv[1], "beat") == 0)
    beat(ep.mesh, ep.options, std::lround(s.period_ms() / ep.options.dt_ms));
  return 0;
}
