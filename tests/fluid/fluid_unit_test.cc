// Unit tier: the Poisson solver (self-test, manufactured solution), parameter checks, the
// stability detector, the Darcy sink, the body-force hook.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "solver/core/errors.h"
#include "solver/fluid/fluid.h"
#include "solver/fluid/operators.h"
#include "solver/fluid/pressure/poisson.h"
#include "solver/fluid/verification_cases.h"

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
  p.viscosity_model = "carreau_yasuda";
  EXPECT_NE(message(p).find("known: newtonian"), std::string::npos);
  EXPECT_THROW(parse_verification_case("kovasznay"), InputError);
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
