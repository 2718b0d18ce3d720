// Verification tier of the multirate scheduler against exact solutions:
// - two masses on springs split into two modules (each sub-cycling at its own step): loose and
//   strong coupling converge to the exact normal-mode solution at first order in Δt_sync;
// - the added-mass problem (Causin, Gerbeau & Nobile 2005, CMAME 194:4506): a structure of
//   mass m_s in a "fluid" that loads it with −m_a a. Loose (explicit) coupling amplifies the
//   interface error by −m_a/m_s per interval and blows up for m_a > m_s; strong coupling with
//   relaxation converges to (m_s + m_a) x'' = −k x. This is the scheduler's tested argument for
//   the coupling's stability at a given step (issue #9 reuses it).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "solver/core/errors.h"
#include "solver/coupling/scheduler.h"
#include "toy_modules.h"

namespace systole::coupling {
namespace {

using testing::AddedMassFluid;
using testing::Oscillator;

// Chain: wall -k1- m1 -k12- m2 -k2- wall, x1(0) = 1, x2(0) = 0, at rest.
constexpr double kM1 = 1, kM2 = 2, kK1 = 1, kK12 = 0.5, kK2 = 1.5;

// Exact solution by normal modes: y = M^{1/2} x turns M x'' = −K x into y'' = −A y with
// A = M^{-1/2} K M^{-1/2} symmetric; its 2×2 eigenpairs in closed form.
std::array<double, 2> exact_chain(double t) {
  const double s1 = std::sqrt(kM1), s2 = std::sqrt(kM2);
  const double a = (kK1 + kK12) / kM1, d = (kK2 + kK12) / kM2, b = -kK12 / (s1 * s2);
  const double mean = 0.5 * (a + d), radius = std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  const double y0[2] = {s1 * 1.0, s2 * 0.0};
  double y[2] = {0, 0};
  for (double lambda : {mean - radius, mean + radius}) {
    double v[2] = {b, lambda - a};  // (A − λ) v = 0, b != 0 here
    const double n = std::hypot(v[0], v[1]);
    v[0] /= n;
    v[1] /= n;
    const double c = (v[0] * y0[0] + v[1] * y0[1]) * std::cos(std::sqrt(lambda) * t);
    y[0] += c * v[0];
    y[1] += c * v[1];
  }
  return {y[0] / s1, y[1] / s2};
}

struct ChainRun {
  double max_error;
  SchedulerStats stats;
};

ChainRun run_chain(double sync_step, CouplingMode mode) {
  Oscillator a("mass_1", kM1, kK1, kK12, 1, 0.002), b("mass_2", kM2, kK2, kK12, 0, 0.002);
  std::vector<Stage> stages{
      {&a, {{.name = "x_1", .read = [&](std::vector<double>& d) { d.assign(1, a.x()); },
             .write = [&](const std::vector<double>& d) { b.partner_ = d[0]; }}}},
      {&b, {{.name = "x_2", .read = [&](std::vector<double>& d) { d.assign(1, b.x()); },
             .write = [&](const std::vector<double>& d) { a.partner_ = d[0]; }}}}};
  SchedulerOptions options;
  options.sync_step_ms = sync_step;
  options.mode = mode;
  options.strong_tolerance = 1e-12;
  options.strong_max_iterations = 60;
  Scheduler scheduler(stages, options);
  double worst = 0;
  for (int n = 1; n * 0.4 <= 8 + 1e-9; ++n) {
    scheduler.advance_to(n * 0.4);
    const std::array<double, 2> e = exact_chain(n * 0.4);
    worst = std::max({worst, std::abs(a.x() - e[0]), std::abs(b.x() - e[1])});
  }
  return {worst, scheduler.stats()};
}

TEST(CouplingVerification, LooseAndStrongCouplingConvergeAtFirstOrder) {
  for (CouplingMode mode : {CouplingMode::loose, CouplingMode::strong}) {
    const double steps[3] = {0.1, 0.05, 0.025};
    double error[3];
    for (int i = 0; i < 3; ++i) {
      const ChainRun r = run_chain(steps[i], mode);
      error[i] = r.max_error;
      if (mode == CouplingMode::strong) {
        EXPECT_EQ(r.stats.unconverged_intervals, 0);
        EXPECT_LT(r.stats.max_final_residual, 1e-12);
      }
    }
    const double order_1 = std::log2(error[0] / error[1]), order_2 = std::log2(error[1] / error[2]);
    std::printf("%s: errors %.3e %.3e %.3e, orders %.3f %.3f\n", mode == CouplingMode::loose ? "loose" : "strong",
                error[0], error[1], error[2], order_1, order_2);
    EXPECT_NEAR(order_1, 1.0, 0.15);
    EXPECT_NEAR(order_2, 1.0, 0.1);
    // The internal Verlet steps (2e-3 of the period-scale bound) are not what is measured.
    EXPECT_GT(error[2], 1e-4);
  }
}

struct AddedMassSetup {
  Oscillator structure{"toy_structure", 1.0, 1.0, 0, 1.0, 0.002};
  AddedMassFluid fluid;
  std::vector<Stage> stages;
  explicit AddedMassSetup(double added_mass) : fluid(added_mass, 0.05) {
    // Fig. 6 order: the fluid first (its load from the structure's latest acceleration), then
    // the structure with the new load. Only the load is relaxed.
    stages = {{&fluid, {{.name = "load", .read = [this](std::vector<double>& d) { d.assign(1, fluid.load()); },
                         .write = [this](const std::vector<double>& d) { structure.force_ = d[0]; }}}},
              {&structure,
               {{.name = "acceleration",
                 .read = [this](std::vector<double>& d) { d.assign(1, structure.acceleration()); },
                 .write = [this](const std::vector<double>& d) { fluid.structure_acceleration_ = d[0]; },
                 .relaxed = false}}}};
  }
};

TEST(CouplingVerification, LooseCouplingBlowsUpWhenTheAddedMassExceedsTheStructuresMass) {
  AddedMassSetup setup(2.0);  // m_a / m_s = 2: amplification 2 per interval
  SchedulerOptions options;
  options.sync_step_ms = 0.1;
  Scheduler scheduler(setup.stages, options);
  try {
    scheduler.advance_to(20);
    FAIL() << "loose coupling at m_a/m_s = 2 did not blow up";
  } catch (const InstabilityError& e) {
    EXPECT_EQ(e.module(), "toy_structure");
  }
  // Below the threshold (m_a/m_s = 0.5) the same loose scheme is stable and converges to
  // (m_s + m_a) x'' = −k x as the interval shrinks (first order: the error halves).
  double error[2];
  for (int i = 0; i < 2; ++i) {
    AddedMassSetup light(0.5);
    SchedulerOptions o = options;
    o.sync_step_ms = i == 0 ? 0.1 : 0.05;
    Scheduler ok(light.stages, o);
    double worst = 0, amplitude = 0;
    for (int n = 1; n <= 40; ++n) {
      EXPECT_NO_THROW(ok.advance_to(n * 0.5));
      worst = std::max(worst, std::abs(light.structure.x() - std::cos(n * 0.5 / std::sqrt(1.5))));
      amplitude = std::max(amplitude, std::abs(light.structure.x()));
    }
    EXPECT_LT(amplitude, 1.0 + 1e-3);
    error[i] = worst;
  }
  std::printf("loose, m_a/m_s = 0.5: max error %.3e (sync 0.1), %.3e (sync 0.05)\n", error[0], error[1]);
  EXPECT_NEAR(std::log2(error[0] / error[1]), 1.0, 0.2);
}

TEST(CouplingVerification, StrongCouplingWithRelaxationConvergesToTheAddedMassSolution) {
  for (Relaxation relaxation : {Relaxation::constant, Relaxation::aitken}) {
    const double steps[3] = {0.1, 0.05, 0.025};
    double error[3];
    for (int i = 0; i < 3; ++i) {
      AddedMassSetup setup(2.0);
      SchedulerOptions options;
      options.sync_step_ms = steps[i];
      options.mode = CouplingMode::strong;
      options.relaxation = relaxation;
      options.relaxation_factor = 0.5;  // the fixed point map's factor: |1 − 0.5 (1 + 2)| = 0.5
      options.strong_tolerance = 1e-10;
      options.strong_max_iterations = 60;
      Scheduler scheduler(setup.stages, options);
      double worst = 0;
      for (int n = 1; n * 0.5 <= 10 + 1e-9; ++n) {
        scheduler.advance_to(n * 0.5);
        worst = std::max(worst, std::abs(setup.structure.x() - std::cos(n * 0.5 / std::sqrt(3.0))));
      }
      error[i] = worst;
      EXPECT_EQ(scheduler.stats().unconverged_intervals, 0);
      const double passes_per_interval =
          static_cast<double>(scheduler.stats().passes) / static_cast<double>(scheduler.stats().intervals);
      std::printf("%s relaxation, sync step %.3f: %.1f passes per interval, max error %.3e\n",
                  relaxation == Relaxation::aitken ? "Aitken" : "constant", steps[i], passes_per_interval, worst);
      if (relaxation == Relaxation::aitken) {
        EXPECT_LT(passes_per_interval, 20);
      }
    }
    EXPECT_NEAR(std::log2(error[0] / error[1]), 1.0, 0.2);
    EXPECT_NEAR(std::log2(error[1] / error[2]), 1.0, 0.2);
  }
}

}  // namespace
}  // namespace systole::coupling
