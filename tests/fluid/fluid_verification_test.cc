// Verification tier: observed orders asserted as numbers, exact solutions, round-off
// divergence after every step, mass conservation, energy balance, restart equivalence.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <vector>

#include "solver/fluid/fluid.h"
#include "solver/fluid/verification_cases.h"
#include "solver/fluid/viscosity.h"

namespace systole::fluid {
namespace {
constexpr double kPi = std::numbers::pi;

RunResult run(FluidCaseSpec spec) { return run_verification_case(spec, MPI_COMM_WORLD); }
void print(const char* what, double value) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) std::printf("  [measured] %s = %.6g\n", what, value);
}

TEST(TaylorGreen2D, SecondOrderInSpace) {
  double previous = 0, order = 0;
  for (int n : {16, 32, 64}) {
    FluidCaseSpec s;
    s.case_name = VerificationCase::taylor_green_2d;
    s.nx = s.ny = n;
    s.nz = 2;
    s.reynolds = 100;
    s.end_time = 1.0;
    s.cfl = 0.1;
    s.samples = 2;
    const RunResult r = run(s);
    const double e = r.metrics.at("error_l2_relative");
    EXPECT_LT(r.metrics.at("max_divergence_all_steps"), 1e-11);
    EXPECT_LT(r.metrics.at("mass_flux_relative_variation"), 1e-11);
    if (previous > 0) {
      order = std::log2(previous / e);
      print(("taylor_green_2d space order " + std::to_string(n / 2) + "->" + std::to_string(n)).c_str(), order);
      EXPECT_GE(order, 1.9);
    }
    print(("taylor_green_2d L2 error N=" + std::to_string(n)).c_str(), e);
    previous = e;
  }
}

// Time order on a fixed grid against a fine-Δt reference (Richardson on one grid): Womersley
// flow (an oscillating body force) has a real time dependence, unlike the Taylor–Green decay.
std::vector<double> womersley_u(double dt, double t_end) {
  const grid::Grid g({2, 2, 32, 1, 1, 2});
  const grid::Slabs s(g, MPI_COMM_WORLD);
  FluidParameters p;
  p.reynolds = 100;
  p.adaptive_dt = false;
  p.max_dt = dt;
  FluidSolver f(s, p);
  const double omega = 16.0 / 100;  // Wo = 4
  f.set_body_force([omega](const StepContext& c, const Velocity&, Velocity& force) {
    force.u.fill(std::cos(omega * (c.time + 0.5 * c.dt)));
  });
  f.set_velocity([](double, double, double z) { return std::sin(kPi * z / 2); },
                 [](double, double, double) { return 0.0; }, [](double, double, double) { return 0.0; });
  f.advance_to(t_end);
  std::vector<double> out;
  for (int k = 0; k < f.velocity().u.k_count(); ++k) out.push_back(f.velocity().u(0, 0, k));
  return out;
}

TEST(Womersley, SecondOrderInTime) {
  const double t_end = 4.0;
  const auto ref = womersley_u(0.04 / 32, t_end);
  double previous = 0;
  for (double dt : {0.04, 0.02, 0.01}) {
    const auto u = womersley_u(dt, t_end);
    double e = 0;
    for (std::size_t k = 0; k < u.size(); ++k) e = std::max(e, std::abs(u[k] - ref[k]));
    double eg = 0;
    MPI_Allreduce(&e, &eg, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    if (previous > 0) {
      const double order = std::log2(previous / eg);
      print(("time order dt=" + std::to_string(dt)).c_str(), order);
      EXPECT_GT(order, 1.85);
      EXPECT_LT(order, 2.3);
    }
    previous = eg;
  }
}

TEST(Poiseuille, SteadyProfileSecondOrder) {
  double previous = 0;
  for (int n : {16, 32}) {
    FluidCaseSpec s;
    s.case_name = VerificationCase::poiseuille;
    s.nx = s.ny = 2;
    s.nz = n;
    s.reynolds = 10;
    s.end_time = 14;
    s.max_dt = 1;
    s.samples = 2;
    const RunResult r = run(s);
    const double e = r.metrics.at("error_linf_relative");
    print(("poiseuille Linf error nz=" + std::to_string(n)).c_str(), e);
    EXPECT_LT(e, 1.1 / (n * n));  // the error is the wall closure's, Δz² exactly
    EXPECT_LT(r.metrics.at("mass_flux_relative_variation"), 1e-12);
    EXPECT_LT(r.metrics.at("max_divergence_all_steps"), 1e-11);
    if (previous > 0) {
      print("poiseuille order", std::log2(previous / e));
      EXPECT_GE(std::log2(previous / e), 1.9);
    }
    previous = e;
  }
}

// (b) of issue 6 item 2: steady shear-thinning plane Poiseuille flow between the z walls against
// the 1-D reference (plane_poiseuille_velocity: the stress balance τ = G (h/2 − z) inverted
// through the Carreau–Yasuda law and integrated by Gauss–Legendre quadrature, no grid). The
// law's constants (nondimensional) are chosen so that λγ̇ runs from 0 at the centre to ≈ 11.5
// at the walls, where ν has fallen to 0.44 ν0 (the power-law regime, n = 0.5), and so that the
// steady state is reached in seconds: the flow starts on the reference sampled at the faces and
// runs 16 time units (≈ 6 relaxation times), so what is measured is the discrete steady state
// (the change over the last time unit is checked to be far below the error).
CarreauYasuda shear_thinning_law() { return {0.1, 0.02, 1.0, 0.5, 2.0}; }
struct ShearThinningPoiseuille {
  double l2 = 0, linf = 0, drift = 0, peak = 0, nu_max = 0, nu_min = 1e300;
  long steps = 0;
};
ShearThinningPoiseuille shear_thinning_poiseuille(int nz) {
  const CarreauYasuda law = shear_thinning_law();
  const double G = 1.0;
  const grid::Grid g({2, 2, nz, 1, 1, 1});
  const grid::Slabs s(g, MPI_COMM_WORLD);
  FluidParameters p;
  p.viscosity_model = "carreau_yasuda";
  p.carreau_yasuda = law;
  p.max_dt = 1;
  FluidSolver f(s, p);
  f.set_body_force([G](const StepContext&, const Velocity&, Velocity& force) { force.u.fill(G); });
  std::vector<double> ref(nz);
  for (int k = 0; k < nz; ++k) ref[k] = plane_poiseuille_velocity(law, G, 1.0, g.z(grid::Location::x_face, k));
  ShearThinningPoiseuille out;
  out.peak = plane_poiseuille_velocity(law, G, 1.0, 0.5);
  f.set_velocity([&](double, double, double z) { return ref[static_cast<std::size_t>(std::lround(z / g.dz() - 0.5))]; },
                 [](double, double, double) { return 0.0; }, [](double, double, double) { return 0.0; });
  const double t_end = 16.0;
  f.advance_to(t_end - 1);
  std::vector<double> before;
  for (int k = 0; k < f.velocity().u.k_count(); ++k) before.push_back(f.velocity().u(0, 0, k));
  f.advance_to(t_end);
  double sum = 0, mx = 0, drift = 0;
  for (int k = 0; k < f.velocity().u.k_count(); ++k) {
    const double e = f.velocity().u(0, 0, k) - ref[s.k_begin() + k];
    sum += e * e;
    mx = std::max(mx, std::abs(e));
    drift = std::max(drift, std::abs(f.velocity().u(0, 0, k) - before[k]));
  }
  double in[1] = {sum}, total[1];
  MPI_Allreduce(in, total, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  double maxes[2] = {mx, drift}, gmax[2];
  MPI_Allreduce(maxes, gmax, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  out.l2 = std::sqrt(total[0] / nz) / out.peak;
  out.linf = gmax[0] / out.peak;
  out.drift = gmax[1] / out.peak;
  out.nu_max = f.max_viscosity();
  out.steps = f.steps();
  return out;
}

TEST(Poiseuille, ShearThinningSteadyProfileSecondOrder) {
  const CarreauYasuda law = shear_thinning_law();
  const double wall_shear = shear_rate_for_stress(law, 0.5);  // τ_w = G h/2
  print("carreau_yasuda poiseuille wall shear rate", wall_shear);
  print("carreau_yasuda poiseuille nu(wall) / nu0", law(wall_shear) / law.nu0);
  print("carreau_yasuda poiseuille reference peak / Newtonian(nu0) peak",
        plane_poiseuille_velocity(law, 1.0, 1.0, 0.5) / (1.0 / (8 * law.nu0)));
  double previous = 0, previous_linf = 0;
  for (int n : {16, 32, 64}) {
    const ShearThinningPoiseuille r = shear_thinning_poiseuille(n);
    print(("carreau_yasuda poiseuille L2 error nz=" + std::to_string(n)).c_str(), r.l2);
    print(("carreau_yasuda poiseuille Linf error nz=" + std::to_string(n)).c_str(), r.linf);
    print(("carreau_yasuda poiseuille change over the last time unit nz=" + std::to_string(n)).c_str(), r.drift);
    print(("carreau_yasuda poiseuille steps nz=" + std::to_string(n)).c_str(), static_cast<double>(r.steps));
    EXPECT_LT(r.drift, 0.01 * r.l2);  // steady: the error measured is the discretisation's
    if (previous > 0) {
      // The observed order approaches 2 from above (2.21, 2.10 in L2: a pre-asymptotic h³ term
      // of the nonlinear law); the finest pair must be within ±0.15 of 2 in both norms.
      const double order = std::log2(previous / r.l2), order_linf = std::log2(previous_linf / r.linf);
      const std::string pair = std::to_string(n / 2) + "->" + std::to_string(n);
      print(("carreau_yasuda poiseuille L2 order " + pair).c_str(), order);
      print(("carreau_yasuda poiseuille Linf order " + pair).c_str(), order_linf);
      EXPECT_GT(order, 1.9);
      EXPECT_GT(order_linf, 1.9);
      EXPECT_LT(order, n == 64 ? 2.15 : 2.3);
      EXPECT_LT(order_linf, n == 64 ? 2.15 : 2.3);
    }
    previous = r.l2;
    previous_linf = r.linf;
  }
}

// A Taylor–Green-like decay (16×16×8, free-slip walls) to t = 2 with the given parameters: the
// discrete energy balance E(T) − E(0) + ∫ε dt (trapezoidal in time, ε the operator's exact sink),
// over E(0); whether the decay was monotone; the largest divergence and the largest ν over the run.
struct EnergyRun {
  double balance = 0, energy_ratio = 0, max_div = 0, nu_max = 0;
  bool monotone = true;
};
EnergyRun taylor_green_3d_energy(FluidParameters p) {
  const grid::Grid g({16, 16, 8, 2 * kPi, 2 * kPi, kPi});
  const grid::Slabs s(g, MPI_COMM_WORLD);
  p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
  p.cfl = 0.1;
  FluidSolver f(s, p);
  f.set_velocity([](double x, double y, double z) { return std::sin(x) * std::cos(y) * std::cos(z); },
                 [](double x, double y, double z) { return -std::cos(x) * std::sin(y) * std::cos(z); },
                 [](double, double, double) { return 0.0; });
  const FlowDiagnostics d0 = f.diagnostics();
  EnergyRun r;
  double integral = 0, eps_prev = d0.dissipation, e_prev = d0.kinetic_energy;
  while (f.time() < 2.0 * (1 - 1e-14)) {
    const double dt = f.advance(2.0);
    const FlowDiagnostics d = f.diagnostics();
    integral += 0.5 * dt * (d.dissipation + eps_prev);
    eps_prev = d.dissipation;
    r.monotone = r.monotone && d.kinetic_energy < e_prev;
    e_prev = d.kinetic_energy;
    r.max_div = std::max(r.max_div, d.max_divergence);
    r.nu_max = std::max(r.nu_max, f.max_viscosity());
  }
  r.balance = std::abs(e_prev - d0.kinetic_energy + integral) / d0.kinetic_energy;
  r.energy_ratio = e_prev / d0.kinetic_energy;
  return r;
}

// The variable-viscosity operator in 3-D with the nonlinear terms: a Taylor–Green-like decay
// (free-slip walls) of a strongly shear-thinning fluid conserves energy discretely,
// E(T) − E(0) + ∫ε dt ≈ 0 (ε the exact discrete sink of the operator; the residue is the time
// discretisation's), decays monotonically and keeps the divergence at round-off.
TEST(TaylorGreen3D, ShearThinningEnergyBalance) {
  FluidParameters p;
  p.viscosity_model = "carreau_yasuda";
  p.carreau_yasuda = {0.05, 0.005, 5.0, 0.4, 2.0};  // ν(γ̇ = 1) = 0.44 ν0, ν(γ̇ = 3) = 0.28 ν0
  const EnergyRun r = taylor_green_3d_energy(p);
  print("carreau_yasuda taylor_green_3d energy balance relative error", r.balance);
  print("carreau_yasuda taylor_green_3d energy decay E(2)/E(0)", r.energy_ratio);
  print("carreau_yasuda taylor_green_3d largest viscosity / nu0", r.nu_max / 0.05);
  EXPECT_LT(r.balance, 2e-3);
  EXPECT_TRUE(r.monotone);
  EXPECT_LT(r.max_div, 1e-11);
  EXPECT_LT(r.energy_ratio, 0.9);
}

// The same balance with Vreman's eddy viscosity at Re = 3000 on a 16×16×8 grid (far from
// resolved): E(T) − E(0) + ∫ε dt ≈ 0 with ε the operator's exact sink for the cell-wise ν, the
// decay monotone, and the model dissipating more than the molecular viscosity alone.
TEST(TaylorGreen3D, VremanEnergyBalance) {
  FluidParameters p;
  p.reynolds = 3000;
  const EnergyRun newtonian = taylor_green_3d_energy(p);
  p.subgrid_model = "vreman";
  const EnergyRun r = taylor_green_3d_energy(p);
  print("vreman taylor_green_3d Re 3000 energy balance relative error", r.balance);
  print("vreman taylor_green_3d Re 3000 largest nu / molecular", r.nu_max * 3000);
  EXPECT_LT(r.balance, 2e-3);
  EXPECT_TRUE(r.monotone);
  EXPECT_LT(r.max_div, 1e-11);
  EXPECT_GT(r.nu_max * 3000, 2);  // the eddy part is what dissipates here
  print("taylor_green_3d Re 3000 E(2)/E(0) newtonian", newtonian.energy_ratio);
  print("taylor_green_3d Re 3000 E(2)/E(0) vreman", r.energy_ratio);
  EXPECT_LT(r.energy_ratio, newtonian.energy_ratio);
}

TEST(Couette, LinearProfileIsExact) {
  FluidCaseSpec s;
  s.case_name = VerificationCase::couette;
  s.nx = s.ny = 2;
  s.nz = 16;
  s.reynolds = 10;
  s.end_time = 14;
  s.max_dt = 1;
  s.samples = 2;
  const RunResult r = run(s);
  print("couette Linf error", r.metrics.at("error_linf_relative"));
  EXPECT_LT(r.metrics.at("error_linf_relative"), 1e-5);  // the decaying start-up transient
}

// Vreman's eddy viscosity is exactly zero in a unidirectional shear flow: the Womersley flow
// (u(z, t) only, an oscillating body force) with the model is the Newtonian one to round-off
// (the variable-viscosity operator with a uniform ν equals the Newtonian Laplacian up to the
// round-off divergence). A model with ν_e ≠ 0 in shear (Smagorinsky's) would change it.
TEST(Womersley, VremanLeavesAUnidirectionalShearFlowAlone) {
  FluidCaseSpec s;
  s.case_name = VerificationCase::womersley;
  s.womersley_number = 4;
  s.nx = s.ny = 2;
  s.nz = 32;
  s.reynolds = 100;
  s.end_time = 2 * kPi / (16.0 / 100);  // one period
  s.max_dt = 1;
  s.samples = 10;
  const RunResult newtonian = run(s);
  s.subgrid_model = "vreman";
  const RunResult vreman = run(s);
  const double a = newtonian.metrics.at("error_linf_max_over_samples_relative"),
               b = vreman.metrics.at("error_linf_max_over_samples_relative");
  print("womersley Wo=4 max error / peak newtonian", a);
  print("womersley Wo=4 max error / peak vreman", b);
  EXPECT_GT(a, 1e-5);  // a discretisation error to compare
  EXPECT_NEAR(b, a, 1e-12);
}

// The model on a smooth flow is an O(Δ²) extra viscosity: the 2-D Taylor–Green decay with it
// converges to the exact (Newtonian) solution at second order, its error a little above the
// Newtonian one at each grid.
TEST(TaylorGreen2D, VremanKeepsSecondOrderInSpace) {
  double previous = 0;
  for (int n : {16, 32, 64}) {
    FluidCaseSpec s;
    s.case_name = VerificationCase::taylor_green_2d;
    s.nx = s.ny = n;
    s.nz = 2;
    s.reynolds = 100;
    s.end_time = 1.0;
    s.cfl = 0.1;
    s.samples = 2;
    const double newtonian = run(s).metrics.at("error_l2_relative");
    s.subgrid_model = "vreman";
    const RunResult r = run(s);
    const double e = r.metrics.at("error_l2_relative");
    print(("vreman taylor_green_2d L2 error N=" + std::to_string(n)).c_str(), e);
    print(("vreman taylor_green_2d L2 error / newtonian's N=" + std::to_string(n)).c_str(), e / newtonian);
    EXPECT_GT(e, newtonian);
    EXPECT_LT(r.metrics.at("max_divergence_all_steps"), 1e-11);
    if (previous > 0) {
      const double order = std::log2(previous / e);
      print(("vreman taylor_green_2d space order " + std::to_string(n / 2) + "->" + std::to_string(n)).c_str(), order);
      EXPECT_GT(order, 1.85);
      EXPECT_LT(order, 2.3);
    }
    previous = e;
  }
}

TEST(Womersley, MatchesTheAnalyticSolutionWithinOnePercent) {
  for (auto [wo, nz] : {std::pair{4.0, 32}, std::pair{12.0, 96}}) {
    FluidCaseSpec s;
    s.case_name = VerificationCase::womersley;
    s.womersley_number = wo;
    s.nx = s.ny = 2;
    s.nz = nz;
    s.reynolds = 100;
    const double period = 2 * kPi / (wo * wo / 100);
    s.end_time = 2 * period;
    s.max_dt = 1;
    s.samples = 40;
    const RunResult r = run(s);
    const double e = r.metrics.at("error_linf_max_over_samples_relative");
    print(("womersley Wo=" + std::to_string(wo) + " max error / peak").c_str(), e);
    EXPECT_LT(e, 0.01);
    EXPECT_LT(r.metrics.at("max_divergence_all_steps"), 1e-11);
  }
}

TEST(TaylorGreen3D, EnergyBalanceAndRoundOffDivergence) {
  FluidCaseSpec s;
  s.case_name = VerificationCase::taylor_green_3d;
  s.nx = s.ny = 32;
  s.nz = 16;
  s.reynolds = 100;
  s.end_time = 2;
  s.samples = 4;
  const RunResult r = run(s);
  print("taylor_green_3d energy balance relative error", r.metrics.at("energy_balance_relative_error"));
  print("taylor_green_3d max divergence", r.metrics.at("max_divergence_all_steps"));
  EXPECT_LT(r.metrics.at("energy_balance_relative_error"), 2e-3);
  EXPECT_LT(r.metrics.at("max_divergence_all_steps"), 1e-11);
  const auto& ke = r.series[1].values;
  for (std::size_t i = 1; i < ke.size(); ++i) EXPECT_LT(ke[i], ke[i - 1]);
}

TEST(Checkpoint, RestartEqualsAStraightRunBitwise) {
  const grid::Grid g({16, 16, 8, 2 * kPi, 2 * kPi, kPi});
  const grid::Slabs s(g, MPI_COMM_WORLD);
  FluidParameters p;
  p.reynolds = 200;
  p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
  auto u0 = [](double x, double y, double z) { return std::sin(x) * std::cos(y) * std::cos(z); };
  auto v0 = [](double x, double y, double z) { return -std::cos(x) * std::sin(y) * std::cos(z); };
  auto w0 = [](double, double, double) { return 0.0; };
  FluidSolver straight(s, p);
  straight.set_velocity(u0, v0, w0);
  for (int n = 0; n < 20; ++n) straight.advance();

  const auto file = std::filesystem::temp_directory_path() / "systole_fluid_checkpoint_test.h5";
  {
    FluidSolver first(s, p);
    first.set_velocity(u0, v0, w0);
    for (int n = 0; n < 10; ++n) first.advance();
    first.write_checkpoint(file);
  }
  FluidSolver second(s, p);
  second.restore_checkpoint(file);
  for (int n = 0; n < 10; ++n) second.advance();
  EXPECT_EQ(second.time(), straight.time());
  EXPECT_EQ(second.steps(), straight.steps());
  const Velocity &a = straight.velocity(), &b = second.velocity();
  long differences = 0;
  for (int k = 0; k < a.u.k_count(); ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i)
        differences += (a.u(i, j, k) != b.u(i, j, k)) + (a.v(i, j, k) != b.v(i, j, k)) +
                       (a.w(i, j, k) != b.w(i, j, k)) + (straight.pressure()(i, j, k) != second.pressure()(i, j, k));
  EXPECT_EQ(differences, 0);
  // Field output: HDF5 + XDMF side by side.
  const auto fields = std::filesystem::temp_directory_path() / "systole_fluid_fields_test.h5";
  second.write_fields(fields);
  EXPECT_TRUE(std::filesystem::exists(fields));
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) {
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(fields).replace_extension(".xmf")));
  }
}

}  // namespace
}  // namespace systole::fluid
