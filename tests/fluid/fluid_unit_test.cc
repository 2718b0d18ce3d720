// Unit tier: the Poisson solver (self-test, manufactured solution), parameter checks, the
// stability detector, the Darcy sink, the body-force hook.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "solver/core/errors.h"
#include "solver/fluid/fluid.h"
#include "solver/fluid/operators.h"
#include "solver/fluid/pressure/poisson.h"
#include "solver/fluid/verification_cases.h"
#include "solver/fluid/viscosity.h"

namespace systole::fluid {
namespace {
using grid::BoxSpec;
using grid::Grid;
using grid::Slabs;
constexpr double kPi = std::numbers::pi;

TEST(Poisson, SelfTestProjectsNoiseToRoundOff) {
  const Slabs s(Grid({16, 12, 10, 1, 2, 3}), MPI_COMM_WORLD);
  const PoissonSolver p(s);
  EXPECT_LT(p.self_test_relative_divergence(), 1e-12);
  EXPECT_TRUE(p.warnings().empty());
}

TEST(Poisson, SolvesTheDiscreteProblemExactly) {
  // φ = cos(2πx/Lx) cos(πz/Lz)·… is not a discrete eigenfunction, so instead check L(solve(r)) = r
  // for a zero-mean r.
  const Grid g({8, 6, 10, 1, 1, 1});
  const Slabs s(g, MPI_COMM_WORLD);
  PoissonSolver p(s);
  grid::CellField r(s), phi(s);
  double mean = 0;
  for (int k = 0; k < r.k_count(); ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 8; ++i) r(i, j, k) = std::sin(1.0 + i * 0.7 + j * 1.3 + (s.k_begin() + k) * 0.4);
  for (int k = 0; k < r.k_count(); ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 8; ++i) mean += r(i, j, k);
  double total = 0;
  MPI_Allreduce(&mean, &total, 1, MPI_DOUBLE, MPI_SUM, s.comm());
  total /= static_cast<double>(g.cells());
  for (int k = 0; k < r.k_count(); ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 8; ++i) r(i, j, k) -= total;
  p.solve(r, phi);
  grid::exchange_halos(phi, s);
  if (s.owns_bottom_wall())
    for (int j = -1; j <= 6; ++j)
      for (int i = -1; i <= 8; ++i) phi(i, j, -1) = phi(i, j, 0);
  if (s.owns_top_wall())
    for (int j = -1; j <= 6; ++j)
      for (int i = -1; i <= 8; ++i) phi(i, j, phi.k_count()) = phi(i, j, phi.k_count() - 1);
  double worst = 0;
  const double a = 1 / (g.dx() * g.dx()), b = 1 / (g.dy() * g.dy()), c = 1 / (g.dz() * g.dz());
  for (int k = 0; k < r.k_count(); ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 8; ++i) {
        const double lap = a * (phi(i + 1, j, k) - 2 * phi(i, j, k) + phi(i - 1, j, k)) +
                           b * (phi(i, j + 1, k) - 2 * phi(i, j, k) + phi(i, j - 1, k)) +
                           c * (phi(i, j, k + 1) - 2 * phi(i, j, k) + phi(i, j, k - 1));
        worst = std::max(worst, std::abs(lap - r(i, j, k)));
      }
  EXPECT_LT(worst, 1e-10);
}

TEST(Poisson, WarnsAboutSlowFftSizes) {
  const Slabs s(Grid({22, 8, 4, 1, 1, 1}), MPI_COMM_WORLD);
  const PoissonSolver p(s);
  ASSERT_EQ(p.warnings().size(), 1u);
  EXPECT_NE(p.warnings()[0].find("grid.nx = 22"), std::string::npos);
}

TEST(Poisson, RejectsDirichletWalls) {
  const Slabs s(Grid({8, 8, 4, 1, 1, 1}), MPI_COMM_WORLD);
  PoissonSpec spec;
  spec.top_wall = WallPressureCondition::dirichlet;
  EXPECT_THROW(PoissonSolver(s, spec), InputError);
}

TEST(FluidParameters, BadInputNamesTheField) {
  const Grid g({8, 8, 8, 1, 1, 1});
  auto message = [&](FluidParameters p) {
    try {
      validate(p, g);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  FluidParameters p;
  p.cfl = 1.5;
  EXPECT_NE(message(p).find("fluid.cfl = 1.5"), std::string::npos);
  p = {};
  p.reynolds = -1;
  EXPECT_NE(message(p).find("fluid.reynolds"), std::string::npos);
  p = {};
  p.darcy_regions.push_back({0.5, 1.5, 0, 1, 0, 1});
  EXPECT_NE(message(p).find("fluid.darcy_regions[0]"), std::string::npos);
  p = {};
  p.viscosity_model = "bingham";
  EXPECT_NE(message(p).find("fluid.viscosity_model = 'bingham' is unknown; known: newtonian, carreau_yasuda"),
            std::string::npos);
  p = {};
  p.viscosity_model = "carreau_yasuda";
  EXPECT_EQ(message(p), "");  // the blood default is valid
  p.carreau_yasuda.n = 1.5;
  EXPECT_NE(message(p).find("fluid.carreau_yasuda.n = 1.5 is out of range (0, 1]"), std::string::npos) << message(p);
  p.carreau_yasuda = blood_carreau_yasuda();
  p.carreau_yasuda.nu_inf = 2 * p.carreau_yasuda.nu0;
  EXPECT_NE(message(p).find("fluid.carreau_yasuda.nu_inf"), std::string::npos);
  p = {};  // Vreman's subgrid model
  p.subgrid_model = "smagorinsky";
  EXPECT_NE(message(p).find("fluid.subgrid_model = 'smagorinsky' is unknown; known: none, vreman"), std::string::npos)
      << message(p);
  p.subgrid_model = "vreman";
  EXPECT_EQ(message(p), "");
  p.subgrid_constant = 0;
  EXPECT_NE(message(p).find("fluid.subgrid_constant"), std::string::npos) << message(p);
  p.subgrid_constant = 0.07;
  p.viscosity_model = "carreau_yasuda";
  EXPECT_NE(message(p).find("fluid.subgrid_model = 'vreman' needs fluid.viscosity_model = newtonian"),
            std::string::npos)
      << message(p);
  EXPECT_THROW(parse_verification_case("kovasznay"), InputError);
  FluidCaseSpec spec;
  spec.viscosity_model = "carreau_yasuda";  // taylor_green_2d has no reference for it
  EXPECT_THROW(run_verification_case(spec, MPI_COMM_WORLD), InputError);
}

// ---- Vreman's subgrid eddy viscosity (viscosity.h, operators.h; ours) -----------------------------

// ν_e = c √(B_β/(α:α)) by hand: a unidirectional shear (rank-1 gradient) gives exactly 0; a plane
// strain diag(1, −1, 0) and a solid rotation (α12 = −1, α21 = 1) both give β11 = β22 = Δ², the
// rest 0, so B_β = Δ⁴, α:α = 2 and ν_e = c Δ²/√2; with Δx ≠ Δy the strain gives c ΔxΔy/√2; ν_e
// scales with Δ² and with |α|.
TEST(Vreman, HandValuesAndZeroInUnidirectionalShear) {
  const double c = 0.07, h = 0.1;
  std::array<double, 9> a{};
  EXPECT_EQ(vreman_eddy_viscosity(a, h, h, h, c), 0.0);  // at rest
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      a = {};
      a[3 * i + j] = 2.5;  // ∂u_j/∂x_i alone: a shear (i ≠ j) or a 1-D stretch (i = j)
      EXPECT_EQ(vreman_eddy_viscosity(a, h, 0.7 * h, 1.3 * h, c), 0.0) << i << j;
    }
  a = {};
  a[0] = 1, a[4] = -1;  // plane strain
  EXPECT_NEAR(vreman_eddy_viscosity(a, h, h, h, c), c * h * h / std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(vreman_eddy_viscosity(a, h, 2 * h, h, c), c * h * 2 * h / std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(vreman_eddy_viscosity(a, 2 * h, 2 * h, 2 * h, c), 4 * vreman_eddy_viscosity(a, h, h, h, c), 1e-15);
  for (double& x : a) x *= 3;
  EXPECT_NEAR(vreman_eddy_viscosity(a, h, h, h, c), 3 * c * h * h / std::sqrt(2.0), 1e-15);
  a = {};
  a[1] = 1, a[3] = -1;  // solid-body rotation about z: α01 = ∂v/∂x = 1, α10 = ∂u/∂y = −1
  EXPECT_NEAR(vreman_eddy_viscosity(a, h, h, h, c), c * h * h / std::sqrt(2.0), 1e-15);
}

// velocity_gradient_at_cell is exact on a linear field u_j = Σ_i G_ij x_i sampled at the MAC faces.
TEST(Vreman, TheCellGradientIsExactOnALinearField) {
  const int n = 4;  // a 4³ block, the cell (1,1,1) read with its neighbours
  const double dx = 0.3, dy = 0.5, dz = 0.7;
  const double G[3][3] = {{0.3, -1.2, 0.7}, {2.1, 0.4, -0.5}, {-0.8, 1.6, -0.7}};  // G[i][j] = ∂u_j/∂x_i
  std::vector<double> u(n * n * n), v(n * n * n), w(n * n * n);
  auto lin = [&](int comp, double x, double y, double z) { return G[0][comp] * x + G[1][comp] * y + G[2][comp] * z; };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::size_t q = static_cast<std::size_t>(i + n * (j + n * k));
        u[q] = lin(0, i * dx, (j + 0.5) * dy, (k + 0.5) * dz);  // x-face (i, j, k)
        v[q] = lin(1, (i + 0.5) * dx, j * dy, (k + 0.5) * dz);  // y-face
        w[q] = lin(2, (i + 0.5) * dx, (j + 0.5) * dy, k * dz);  // z-face
      }
  const std::ptrdiff_t q = 1 + n * (1 + n * 1);
  const auto a = velocity_gradient_at_cell(u.data(), v.data(), w.data(), q, n, n * n, 1 / dx, 1 / dy, 1 / dz);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(a[3 * i + j], G[i][j], 1e-13) << i << j;
}

// ---- Carreau–Yasuda (viscosity.h) ---------------------------------------------------------------

TEST(CarreauYasuda, BloodLawAtTheSeedScales) {
  // Cho & Kensey 1991 with ρ = 1060 kg/m³, d_m = 24 mm, U_m = 0.6 m/s: ρ U d = 15.264 Pa·s.
  const CarreauYasuda b = blood_carreau_yasuda();
  EXPECT_NEAR(b.nu0, 0.056 / 15.264, 1e-15);
  EXPECT_NEAR(b.nu_inf, 0.00345 / 15.264, 1e-15);
  EXPECT_NEAR(b.lambda, 3.313 * 25, 1e-12);
  EXPECT_EQ(b.n, 0.3568);
  EXPECT_EQ(b.a, 2);
  EXPECT_DOUBLE_EQ(b(0), b.nu0);
  EXPECT_NEAR(b(1e12), b.nu_inf, 1e-6 * b.nu_inf);
  // Monotone shear thinning, and the dimensional law at 100 1/s (= 4 in units of U_m/d_m):
  // μ = 0.00345 + 0.05255 (1 + 331.3²)^(−0.3216) = 0.00568 Pa·s.
  for (double g = 0.01; g < 1e4; g *= 3) EXPECT_LT(b(3 * g), b(g));
  EXPECT_NEAR(b(4.0) * 15.264, 0.00345 + (0.056 - 0.00345) * std::pow(1 + 331.3 * 331.3, (0.3568 - 1) / 2), 1e-15);
}

TEST(CarreauYasuda, StressInversionAndNewtonianLimitOfTheReference) {
  const CarreauYasuda b = blood_carreau_yasuda();
  for (double s : {-50.0, -0.3, 1e-4, 0.02, 1.0, 7.0, 300.0})
    EXPECT_NEAR(shear_rate_for_stress(b, shear_stress(b, s)), s, 1e-13 * std::abs(s));
  // n = 1: ν ≡ ν0 and the reference is the parabola G z (h − z) / (2ν0).
  CarreauYasuda newtonian{0.02, 0.005, 3.0, 1.0, 2.0};
  for (double z : {0.0, 0.1, 0.37, 0.5, 0.8, 1.0})
    EXPECT_NEAR(plane_poiseuille_velocity(newtonian, 0.3, 1.0, z), 0.3 * z * (1 - z) / (2 * 0.02), 1e-14);
}

TEST(CarreauYasuda, ReferenceApproachesThePowerLawSolution) {
  // ν∞ = 0, λ ≫ 1: ν ≈ K γ̇^(n−1), K = ν0 λ^(n−1), whose plane Poiseuille profile is known in
  // closed form: u = n/(n+1) (G/K)^(1/n) [(h/2)^(1+1/n) − |h/2 − z|^(1+1/n)]. An independent check of
  // the quadrature and of the stress inversion (the difference is the 1 in 1 + (λγ̇)^a).
  const double n = 0.5, lambda = 1e6, nu0 = 1.0, G = 2.0, h = 1.0;
  const CarreauYasuda law{nu0, 0.0, lambda, n, 2.0};
  const double K = nu0 * std::pow(lambda, n - 1);
  for (double z : {0.05, 0.2, 0.35, 0.5}) {
    const double exact = n / (n + 1) * std::pow(G / K, 1 / n) *
                         (std::pow(h / 2, 1 + 1 / n) - std::pow(std::abs(h / 2 - z), 1 + 1 / n));
    EXPECT_NEAR(plane_poiseuille_velocity(law, G, h, z) / exact, 1.0, 1e-6) << z;
  }
}

// (a) of issue 6 item 2: Carreau–Yasuda with n = 1 (or ν0 = ν∞) reproduces the Newtonian solver
// to round-off — a 3-D flow with a moving no-slip wall (the wall ghosts of ν) and the nonlinear terms.
TEST(CarreauYasuda, NewtonianLimitReproducesTheNewtonianSolver) {
  const Slabs s(Grid({16, 12, 10, 2 * kPi, 2 * kPi, kPi}), MPI_COMM_WORLD);
  auto run = [&](const FluidParameters& p) {
    auto f = std::make_unique<FluidSolver>(s, p);
    f->set_velocity([](double x, double y, double z) { return std::sin(x) * std::cos(y) * std::sin(z); },
                    [](double x, double y, double z) { return -std::cos(x) * std::sin(y) * std::sin(z) + 0.1 * std::cos(2 * x); },
                    [](double x, double, double z) { return 0.2 * std::sin(x) * std::sin(z); });
    for (int n = 0; n < 30; ++n) f->advance();
    return f;
  };
  FluidParameters newtonian;
  newtonian.reynolds = 50;
  newtonian.top_wall.velocity_x = 0.3;
  const auto ref = run(newtonian);
  FluidParameters equal_limits = newtonian, unit_index = newtonian;
  equal_limits.viscosity_model = unit_index.viscosity_model = "carreau_yasuda";
  equal_limits.carreau_yasuda = {1.0 / 50, 1.0 / 50, 5.0, 0.4, 1.5};  // ν0 = ν∞: ν ≡ 1/Re exactly
  unit_index.carreau_yasuda = {1.0 / 50, 0.003, 5.0, 1.0, 2.0};       // n = 1: ν ≡ ν0 (to round-off)
  for (const FluidParameters* p : {&equal_limits, &unit_index}) {
    const auto cy = run(*p);
    EXPECT_NEAR(cy->time(), ref->time(), 1e-14);
    EXPECT_NEAR(cy->max_viscosity(), 1.0 / 50, 1e-17);
    double worst = 0;
    const Velocity &a = ref->velocity(), &b = cy->velocity();
    for (int k = 0; k < a.u.k_count(); ++k)
      for (int j = 0; j < 12; ++j)
        for (int i = 0; i < 16; ++i)
          worst = std::max({worst, std::abs(a.u(i, j, k) - b.u(i, j, k)), std::abs(a.v(i, j, k) - b.v(i, j, k)),
                            std::abs(a.w(i, j, k) - b.w(i, j, k))});
    double global = 0;
    MPI_Allreduce(&worst, &global, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0) std::printf("  [measured] Carreau-Yasuda Newtonian limit: max |u_CY - u_N| = %.3g\n", global);
    EXPECT_LT(global, 1e-13);
    // Both dissipations are the exact discrete energy sink of their operator: equal for a
    // divergence-free field (⟨|∇u|²⟩ = ⟨2S:S⟩ by summation by parts on the MAC grid).
    EXPECT_NEAR(cy->diagnostics().dissipation, ref->diagnostics().dissipation, 1e-12 * ref->diagnostics().dissipation);
  }
}

TEST(FluidSolver, DtAboveTheCflLimitStopsWithADiagnosis) {
  const Slabs s(Grid({16, 16, 8, 2 * kPi, 2 * kPi, kPi}), MPI_COMM_WORLD);
  FluidParameters p;
  p.reynolds = 3000;
  p.adaptive_dt = false;
  p.max_dt = 1.0;  // CFL ≈ 2.5
  p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
  FluidSolver f(s, p);
  f.set_velocity([](double x, double y, double z) { return std::sin(x) * std::cos(y) * std::cos(z); },
                 [](double x, double y, double z) { return -std::cos(x) * std::sin(y) * std::cos(z); },
                 [](double, double, double) { return 0.0; });
  try {
    for (int n = 0; n < 100; ++n) f.advance();
    FAIL() << "not detected";
  } catch (const InstabilityError& e) {
    EXPECT_EQ(e.module(), "fluid");
    EXPECT_NE(std::string(e.what()).find("CFL"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fastest cell (i,j,k) = ("), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(") mm"), std::string::npos) << e.what();
  }
}

// fluid.cfl_rule: two jets of equal speed, one along x in a band at z ≈ π/4 and one along y in a
// band at z ≈ 3π/4 (each independent of its own direction: discretely divergence-free). With the
// component maxima the step sees both at once, Δt = cfl/(A/dx + A/dy); per cell it sees one,
// Δt = cfl/(A/dx): twice as large. With both jets in the same band one cell holds both maxima
// and the two rules agree.
TEST(FluidSolver, ThePerCellCflRuleSeesJetsInDifferentPlacesSeparately) {
  const Slabs s(Grid({16, 16, 16, 2 * kPi, 2 * kPi, kPi}), MPI_COMM_WORLD);
  auto first_step = [&](const std::string& rule, double z_u, double z_v) {
    FluidParameters p;
    p.reynolds = 3000;
    p.max_dt = 1.0;
    p.cfl_rule = rule;
    p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
    FluidSolver f(s, p);
    const double a = 2.0, width = 0.2;
    auto band = [&](double z, double z0) { return a * std::exp(-(z - z0) * (z - z0) / (width * width)); };
    f.set_velocity([&](double, double y, double z) { return band(z, z_u) * (1 + 0.5 * std::sin(y)); },
                   [&](double x, double, double z) { return band(z, z_v) * (1 + 0.5 * std::cos(x)); },
                   [](double, double, double) { return 0.0; });
    return f.advance();  // the first step is CFL-limited: set_velocity measured the field
  };
  const double apart_maxima = first_step("component_maxima", kPi / 4, 3 * kPi / 4);
  const double apart_per_cell = first_step("per_cell", kPi / 4, 3 * kPi / 4);
  EXPECT_NEAR(apart_per_cell / apart_maxima, 2.0, 1e-6);
  const double together_maxima = first_step("component_maxima", kPi / 4, kPi / 4);
  const double together_per_cell = first_step("per_cell", kPi / 4, kPi / 4);
  EXPECT_NEAR(together_per_cell / together_maxima, 1.0, 1e-12);
  FluidParameters p;
  p.cfl_rule = "local";
  try {
    validate(p, s.grid());
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fluid.cfl_rule = 'local' is unknown; known: component_maxima, per_cell"),
              std::string::npos)
        << e.what();
  }
}

// step_at_cfl (coupling's carry-over reference step): the step another CFL target would choose
// from the same state: the CFL step scales with the target, max_dt caps both, and a target
// outside (0, 1] is an input error naming it.
TEST(FluidSolver, TheStepAtAnotherCflScalesWithItUnderTheSameCap) {
  const Slabs s(Grid({16, 16, 8, 2 * kPi, 2 * kPi, kPi}), MPI_COMM_WORLD);
  FluidParameters p;
  p.reynolds = 3000;
  p.cfl = 0.2;
  p.max_dt = 0.1;
  p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
  FluidSolver f(s, p);
  const double a = 10;  // the CFL step at 0.2: 0.2 / (a (1/dx + 1/dy)) ≈ 0.0025, far below max_dt
  f.set_velocity([a](double x, double y, double z) { return a * std::sin(x) * std::cos(y) * std::cos(z); },
                 [a](double x, double y, double z) { return -a * std::cos(x) * std::sin(y) * std::cos(z); },
                 [](double, double, double) { return 0.0; });
  const double own = f.stable_step();
  EXPECT_LT(own, 0.01);
  EXPECT_EQ(f.step_at_cfl(0.2), own);
  EXPECT_EQ(f.step_at_cfl(0.4), 2 * own);     // 0.4 and 0.2 share their mantissa: exact
  EXPECT_EQ(f.step_at_cfl(0.1), 0.5 * own);
  EXPECT_DOUBLE_EQ(f.step_at_cfl(1.0), 5 * own);  // still below max_dt (round-off: 1/r vs 0.2/r)
  f.set_velocity([](double, double, double) { return 0.0; }, [](double, double, double) { return 0.0; },
                 [](double, double, double) { return 0.0; });
  EXPECT_EQ(f.step_at_cfl(0.4), 0.1);  // at rest: max_dt whatever the target
  EXPECT_EQ(f.step_at_cfl(0.1), 0.1);
  for (double bad : {0.0, -0.2, 1.5, std::nan("")}) {
    try {
      (void)f.step_at_cfl(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("step_at_cfl(cfl = "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("(0, 1]"), std::string::npos) << e.what();
    }
  }
}

// The adaptive step keeps the realised CFL at its target however fast the flow gets, so a
// blow-up would crawl on in ever smaller steps: a CFL step below abort_min_dt stops the run,
// naming the fastest cell; with the guard off the same field just takes a small step.
TEST(FluidSolver, AStepCollapsedBelowTheFloorStopsWithADiagnosis) {
  const Slabs s(Grid({16, 16, 8, 2 * kPi, 2 * kPi, kPi}), MPI_COMM_WORLD);
  auto run = [&](double min_dt) {
    FluidParameters p;
    p.reynolds = 3000;
    p.max_dt = 0.1;
    p.abort_min_dt = min_dt;
    p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
    FluidSolver f(s, p);
    const double a = 1e4;  // CFL step 0.2 / (a (1/dx + 1/dy)) ~ 2.5e-6: 4e4 times below max_dt
    f.set_velocity([a](double x, double y, double z) { return a * std::sin(x) * std::cos(y) * std::cos(z); },
                   [a](double x, double y, double z) { return -a * std::cos(x) * std::sin(y) * std::cos(z); },
                   [](double, double, double) { return 0.0; });
    return f.advance();  // set_velocity measured the field: the first step is CFL-limited
  };
  EXPECT_LT(run(0.0), 1e-4);
  try {
    run(1e-4);
    FAIL() << "not detected";
  } catch (const InstabilityError& e) {
    EXPECT_EQ(e.module(), "fluid");
    EXPECT_NE(std::string(e.what()).find("abort_min_dt"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fastest cell (i,j,k) = ("), std::string::npos) << e.what();
  }
}

TEST(FluidSolver, BlowUpIsDetectedByEnergyGrowthOrNonFiniteValues) {
  const Slabs s(Grid({16, 16, 8, 2 * kPi, 2 * kPi, kPi}), MPI_COMM_WORLD);
  FluidParameters p;
  p.reynolds = 3000;
  p.adaptive_dt = false;
  p.max_dt = 0.6;
  p.abort_cfl = 1e300;  // only the energy and finiteness checks
  p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
  FluidSolver f(s, p);
  f.set_velocity([](double x, double y, double z) { return std::sin(x) * std::cos(y) * std::cos(z); },
                 [](double x, double y, double z) { return -std::cos(x) * std::sin(y) * std::cos(z); },
                 [](double, double, double) { return 0.0; });
  try {
    for (int n = 0; n < 2000; ++n) f.advance();
    FAIL() << "not detected";
  } catch (const InstabilityError& e) {
    const std::string what = e.what();
    EXPECT_TRUE(what.find("kinetic energy") != std::string::npos || what.find("non-finite") != std::string::npos) << what;
    EXPECT_GT(e.time_s(), 0);
  }
}

// A motion starting from rest: the body force jumps ×100 after the first step, so the energy
// grows ~10⁴× in one step, but at a negligible level: below abort_energy_floor it is not a
// blow-up; with the floor at 0 the same run is stopped by the growth check.
TEST(FluidSolver, EnergyGrowthFromRestBelowTheFloorIsNotABlowUp) {
  const Slabs s(Grid({8, 8, 8, 1, 1, 1}), MPI_COMM_WORLD);
  auto run = [&](double floor) {
    FluidParameters p;
    p.reynolds = 100;
    p.abort_energy_floor = floor;
    FluidSolver f(s, p);
    f.set_body_force([](const StepContext& c, const Velocity&, Velocity& force) {
      const double fx = c.step == 0 ? 1e-4 : 1e-2;
      for (int k = 0; k < force.u.k_count(); ++k)
        for (int j = 0; j < 8; ++j)
          for (int i = 0; i < 8; ++i) force.u(i, j, k) = fx;
    });
    for (int n = 0; n < 5; ++n) f.advance();
    return f.diagnostics().kinetic_energy;
  };
  double ke = 0;
  EXPECT_NO_THROW(ke = run(1e-4));
  std::printf("  [measured] kinetic energy after 5 steps %.3g (floor 1e-4)\n", ke);
  EXPECT_LT(ke, 1e-4);
  try {
    run(0.0);
    FAIL() << "the growth check did not fire without the floor";
  } catch (const InstabilityError& e) {
    EXPECT_NE(std::string(e.what()).find("kinetic energy grew"), std::string::npos) << e.what();
  }
}

TEST(FluidSolver, DarcySinkStopsTheFlowInItsRegion) {
  const Grid g({8, 8, 8, 1, 1, 1});
  const Slabs s(g, MPI_COMM_WORLD);
  FluidParameters p;
  p.reynolds = 100;
  p.darcy_regions.push_back({0, 1, 0, 1, 0.25, 0.75});
  p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
  FluidSolver f(s, p);
  f.set_velocity([](double, double, double) { return 1.0; }, [](double, double, double) { return 0.0; },
                 [](double, double, double) { return 0.0; });
  f.advance_to(0.05);
  // Implicit sink: u ≈ Π 1/(1 + Δt/k) ≪ 1 inside, ≈ 1 outside (free-slip walls).
  double inside = 0, outside = 0;
  for (int k = 0; k < f.velocity().u.k_count(); ++k) {
    const double z = g.z(grid::Location::x_face, s.k_begin() + k);
    (z > 0.25 && z < 0.75 ? inside : outside) = std::max(z > 0.25 && z < 0.75 ? inside : outside, std::abs(f.velocity().u(3, 3, k)));
  }
  double in_g = 0, out_g = 0;
  MPI_Allreduce(&inside, &in_g, 1, MPI_DOUBLE, MPI_MAX, s.comm());
  MPI_Allreduce(&outside, &out_g, 1, MPI_DOUBLE, MPI_MAX, s.comm());
  EXPECT_LT(in_g, 0.1);
  EXPECT_GT(out_g, 0.5);
}

// The Darcy sink as a resistance (the afterload, MODEL.md §2; docs/fsei.md session 16 derives
// the heart outlet's resistance from it): a uniform body force f drives a uniform flow along x
// through a slab of the sink across a periodic box; the pressure's periodicity gives f L = u L_d / k,
// u = f k L / L_d, with L_d the slab as its x-faces see it (3 of 16 faces: L / L_d = 16/3). The
// sink is applied to u* (which holds the previous pressure gradient: incremental projection), so the
// steady state satisfies u / k = f - grad p exactly, at any step: measured 8e-9 relative at
// dt = k/10, k/20, k/40 (the transient left after 19 relaxation times k L / L_d).
TEST(FluidSolver, DarcySlabPassesTheDarcyLawsFlowAtAnyStep) {
  const Grid g({16, 4, 4, 1, 0.25, 0.25});
  const Slabs s(g, MPI_COMM_WORLD);
  const double k = 0.01, force = 1.0;
  const double darcy = force * k * 16.0 / 3.0;  // u = f k L / L_d
  for (double dt : {1e-3, 5e-4, 2.5e-4}) {
    FluidParameters p;
    p.reynolds = 100;
    p.darcy_permeability = k;
    p.darcy_regions.push_back({0.28, 0.47, 0, 0.25, 0, 0.25});  // faces x = 5/16, 6/16, 7/16
    p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
    p.adaptive_dt = false;
    p.max_dt = dt;
    FluidSolver f(s, p);
    f.set_body_force([&](const StepContext&, const Velocity&, Velocity& fv) { fv.u.fill(force); });
    f.advance_to(1.0);  // 19 relaxation times
    double lo = 1e300, hi = -1e300;
    for (int kk = 0; kk < f.velocity().u.k_count(); ++kk)
      for (int j = 0; j < g.ny(); ++j)
        for (int i = 0; i < g.nx(); ++i) lo = std::min(lo, f.velocity().u(i, j, kk)), hi = std::max(hi, f.velocity().u(i, j, kk));
    EXPECT_LT(hi - lo, 1e-9 * darcy);  // uniform: the projection leaves no other flow
    std::printf("  [measured] dt %.2g: u %.9f, Darcy's %.9f, relative error %.2g\n", dt, hi, darcy, std::abs(hi - darcy) / darcy);
    EXPECT_LT(std::abs(hi - darcy), 1e-6 * darcy) << dt;
  }
}

TEST(FluidSolver, BodyForceHookSeesUHatAndAcceleratesTheFlow) {
  const Slabs s(Grid({4, 4, 4, 1, 1, 1}), MPI_COMM_WORLD);
  FluidParameters p;
  p.bottom_wall.kind = p.top_wall.kind = WallKind::free_slip;
  p.adaptive_dt = false;
  p.max_dt = 0.01;
  FluidSolver f(s, p);
  int calls = 0;
  f.set_body_force([&](const StepContext& c, const Velocity&, Velocity& force) {
    ++calls;
    EXPECT_NEAR(c.dt, 0.01, 1e-12);
    force.v.fill(2.0);
  });
  f.advance_to(0.1);
  EXPECT_EQ(calls, 10);
  EXPECT_NEAR(f.velocity().v(1, 1, 0), 0.2, 1e-12);
}

}  // namespace
}  // namespace systole::fluid
