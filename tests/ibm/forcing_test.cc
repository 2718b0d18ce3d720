// The multi-direct forcing's passes and the carry-over's increment share (ForcingParameters,
// ours). The passes are Richardson's iteration on A F = (V − I û)/Δt with A = I S (interpolation
// after spreading): a pass multiplies a mode of A with eigenvalue λ by 1 − λ. Measured here with
// MLS: on a lone tiling and on two concentric spheres half a grid spacing apart the passes
// converge (no over-correction where two tilings share a support).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>
#include <cstdio>

#include "solver/core/errors.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/markers.h"
#include "solver/ibm/shapes.h"

namespace systole::ibm {
namespace {
const grid::Grid kGrid({20, 20, 20, 2.0, 2.0, 2.0});  // h = 0.1 (2.4 mm at 24 mm per unit)

BodyOptions rigid_options() {
  BodyOptions o;
  o.mm_per_unit = 24.0;
  return o;
}

struct PassOutcome {
  double slip_before = 0, slip_after = 0;  // rms over the markers, of û and of û + Δt f
};

// Rigid spheres at rest (radii in mm, centred in the box) in the uniform flow u = (1, 0, 0):
// one step of three passes; the slip after them measured on û + Δt f.
PassOutcome three_passes(const std::vector<double>& radii_mm) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  Markers m(kGrid);
  for (std::size_t k = 0; k < radii_mm.size(); ++k)
    m.add_body(sphere_mesh(Vec3(24, 24, 24), radii_mm[k], 3), "sphere_" + std::to_string(k), rigid_options());
  ForcingParameters p;
  p.iterations = 3;
  DirectForcing forcing(slabs, m, p);
  grid::XFaceField u(slabs), fu(slabs);
  grid::YFaceField v(slabs), fv(slabs);
  grid::ZFaceField w(slabs), fw(slabs);
  u.fill(1.0);
  fu.fill(0);
  v.fill(0), fv.fill(0), w.fill(0), fw.fill(0);
  const double dt = 0.01;
  const ForcingReport report = forcing.apply(dt, {u, v, w}, {fu, fv, fw});
  for (int k = 0; k < u.k_count(); ++k)
    for (int j = 0; j < u.ny(); ++j)
      for (int i = 0; i < u.nx(); ++i) {
        u(i, j, k) += dt * fu(i, j, k);
        v(i, j, k) += dt * fv(i, j, k);
        w(i, j, k) += dt * fw(i, j, k);
      }
  grid::exchange_halos(u, slabs);
  grid::exchange_halos(v, slabs);
  grid::exchange_halos(w, slabs);
  PassOutcome o;
  o.slip_before = report.slip_before.rms;
  o.slip_after = forcing.slip({u, v, w}).rms;
  return o;
}

TEST(MultiDirectForcing, ThePassesConvergeOnALoneTilingAndWhereTwoShareASupport) {
  const double r_mm = 7.2;  // 3 h
  const PassOutcome lone = three_passes({r_mm});
  const PassOutcome pair = three_passes({r_mm, r_mm + 1.2});  // 0.5 h apart
  std::printf("  [measured] slip 1 -> %.4f after 3 passes (lone sphere), %.4f (two spheres 0.5 h apart)\n",
              lone.slip_after, pair.slip_after);
  EXPECT_NEAR(lone.slip_before, 1.0, 1e-12);  // u = 1 at every marker, V = 0
  EXPECT_NEAR(pair.slip_before, 1.0, 1e-12);
  // The passes converge in both (|1 − λ| < 1): no over-correction at the overlap.
  EXPECT_LT(lone.slip_after, 0.25);
  EXPECT_LT(pair.slip_after, lone.slip_after);
}

// The carry-over's increment share w (ForcingParameters::carry_over_increment_share, ours): the
// force applied in a step is the same whatever w, the carried force keeps w of the step's
// corrections, and a steady load (a sphere at rest in a uniform flow that the forcing does not
// change: û fixed) is still held: the slip after many steps goes to the same small value and the
// total force to the same value, only more slowly.
struct CarryRun {
  std::vector<double> slip_after;  // per step, rms of û + Δt f at the markers
  std::vector<Vec3> first_force;   // the force density of step 1
  Vec3 total_force = Vec3::Zero(); // of the last step
};

CarryRun steady_load(double share, int steps) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  Markers m(kGrid);
  m.add_body(sphere_mesh(Vec3(24, 24, 24), 7.2, 3), "sphere", rigid_options());
  ForcingParameters p;
  p.iterations = 3;
  p.carry_over = true;
  p.carry_over_increment_share = share;
  DirectForcing forcing(slabs, m, p);
  grid::XFaceField u(slabs), fu(slabs), us(slabs);
  grid::YFaceField v(slabs), fv(slabs), vs(slabs);
  grid::ZFaceField w(slabs), fw(slabs), ws(slabs);
  u.fill(1.0), v.fill(0), w.fill(0);
  const double dt = 0.01;
  CarryRun run;
  for (int n = 0; n < steps; ++n) {
    fu.fill(0), fv.fill(0), fw.fill(0);
    run.total_force = forcing.apply(dt, {u, v, w}, {fu, fv, fw}).total_force;
    if (n == 0) run.first_force = forcing.force_density();
    us.fill(0), vs.fill(0), ws.fill(0);
    for (int k = 0; k < u.k_count(); ++k)
      for (int j = 0; j < u.ny(); ++j)
        for (int i = 0; i < u.nx(); ++i) {
          us(i, j, k) = u(i, j, k) + dt * fu(i, j, k);
          vs(i, j, k) = v(i, j, k) + dt * fv(i, j, k);
          ws(i, j, k) = w(i, j, k) + dt * fw(i, j, k);
        }
    grid::exchange_halos(us, slabs);
    grid::exchange_halos(vs, slabs);
    grid::exchange_halos(ws, slabs);
    run.slip_after.push_back(forcing.slip({us, vs, ws}).rms);
  }
  return run;
}

TEST(CarryOverIncrementShare, KeepsTheAppliedForceAndTheSteadyStateSlowingOnlyTheIntegral) {
  const int steps = 300;
  const CarryRun full = steady_load(1.0, steps), half = steady_load(0.5, steps);
  std::printf("  [measured] slip after step 1, 2, 5, %d: w = 1: %.2e %.2e %.2e %.2e; w = 0.5: %.2e %.2e %.2e %.2e\n", steps,
              full.slip_after[0], full.slip_after[1], full.slip_after[4], full.slip_after.back(), half.slip_after[0],
              half.slip_after[1], half.slip_after[4], half.slip_after.back());
  std::printf("  [measured] total force after %d steps: w = 1: %.6g, w = 0.5: %.6g\n", steps, full.total_force.x(),
              half.total_force.x());
  // Step 1 applies the same force (nothing carried yet).
  ASSERT_EQ(full.first_force.size(), half.first_force.size());
  for (std::size_t b = 0; b < full.first_force.size(); ++b) ASSERT_EQ(full.first_force[b], half.first_force[b]) << b;
  EXPECT_EQ(full.slip_after[0], half.slip_after[0]);
  // From step 2 the half share carries less, so its slip falls more slowly...
  EXPECT_GT(half.slip_after[1], full.slip_after[1]);
  // ...to the same steady state. Both keep lowering the slip after the first steps, down to a floor
  // (≈ 2 % of the first step's here: the part of V − I û that no force spread on this grid can
  // remove, the markers being finer than the grid), the same for both shares: their slips
  // differ at the end by far less than at step 2, and the total force on the fluid agrees.
  EXPECT_LT(full.slip_after.back(), full.slip_after[4]);
  EXPECT_LT(half.slip_after.back(), half.slip_after[4]);
  EXPECT_LT(std::abs(half.slip_after.back() - full.slip_after.back()),
            0.1 * std::abs(half.slip_after[1] - full.slip_after[1]));
  EXPECT_NEAR(half.total_force.x(), full.total_force.x(), 0.01 * std::abs(full.total_force.x()));
  ForcingParameters bad;
  bad.carry_over_increment_share = 0;
  EXPECT_THROW(validate(bad), InputError);
}

// apply()'s per-step factor on the increment share (coupling's step-aware share) is checked:
// outside (0, 1] it is an input error naming it, before anything is spread.
TEST(CarryOverIncrementShare, AStepFactorOutsideZeroToOneIsAnInputError) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  Markers m(kGrid);
  m.add_body(sphere_mesh(Vec3(24, 24, 24), 7.2, 3), "sphere", rigid_options());
  ForcingParameters p;
  p.carry_over = true;
  DirectForcing forcing(slabs, m, p);
  grid::XFaceField u(slabs), fu(slabs);
  grid::YFaceField v(slabs), fv(slabs);
  grid::ZFaceField w(slabs), fw(slabs);
  u.fill(1), fu.fill(0), v.fill(0), fv.fill(0), w.fill(0), fw.fill(0);  // a slip of 1: a force if spread
  for (double bad : {0.0, 1.5}) {
    try {
      forcing.apply(0.01, {u, v, w}, {fu, fv, fw}, Vec3::Zero(), bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("increment_share_factor = "), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(*std::max_element(fu.data(), fu.data() + fu.size()), 0.0);  // nothing spread
  EXPECT_EQ(*std::min_element(fu.data(), fu.data() + fu.size()), 0.0);
}

}  // namespace
}  // namespace systole::ibm
