// The multi-direct forcing's passes and the row-sum scaling of their correction
// (ForcingParameters::row_sum_scaling, ours; docs/fsei.md session 44). The passes are
// Richardson's iteration on A F = (V − I û)/Δt with A = I S (interpolation after spreading): a
// pass multiplies a mode of A with eigenvalue λ by 1 − λ. Measured here with MLS: a lone tiling's
// rows of A sum to about 1/2 (not 1: the forcing volume area × h against the kernel's width), two
// concentric spheres half a grid spacing apart to about 1, so the passes converge in both (no
// over-correction where two tilings share a support: session 43's analysis assumed rows near 2
// there). Scaled per marker by 1/max(r_b, 1/4) the rows sum to 1 and the uniform slip goes in one
// pass up to what the non-uniform modes hold.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>
#include <cstdio>

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
  double row_sum_min = 0, row_sum_max = 0;  // over the markers and components (with the scaling)
};

// Rigid spheres at rest (radii in mm, centred in the box) in the uniform flow u = (1, 0, 0):
// one step of three passes; the slip after them measured on û + Δt f.
PassOutcome three_passes(const std::vector<double>& radii_mm, bool scaled) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  Markers m(kGrid);
  for (std::size_t k = 0; k < radii_mm.size(); ++k)
    m.add_body(sphere_mesh(Vec3(24, 24, 24), radii_mm[k], 3), "sphere_" + std::to_string(k), rigid_options());
  ForcingParameters p;
  p.iterations = 3;
  p.row_sum_scaling = scaled;
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
  o.row_sum_min = 1e300;
  for (const Vec3& r : forcing.row_sums()) {
    o.row_sum_min = std::min(o.row_sum_min, r.minCoeff());
    o.row_sum_max = std::max(o.row_sum_max, r.maxCoeff());
  }
  return o;
}

TEST(RowSumScaling, MakesThePassesConvergeFasterOnALoneTilingAndWhereTwoShareASupport) {
  const double r_mm = 7.2;  // 3 h
  const PassOutcome lone = three_passes({r_mm}, false);
  const PassOutcome lone_scaled = three_passes({r_mm}, true);
  const PassOutcome pair = three_passes({r_mm, r_mm + 1.2}, false);  // 0.5 h apart
  const PassOutcome pair_scaled = three_passes({r_mm, r_mm + 1.2}, true);
  std::printf("  [measured] lone sphere: slip 1 -> %.4f after 3 passes, %.4f scaled; row sums %.3f..%.3f\n",
              lone.slip_after, lone_scaled.slip_after, lone_scaled.row_sum_min, lone_scaled.row_sum_max);
  std::printf("  [measured] two spheres 0.5 h apart: slip 1 -> %.4f, %.4f scaled; row sums %.3f..%.3f\n",
              pair.slip_after, pair_scaled.slip_after, pair_scaled.row_sum_min, pair_scaled.row_sum_max);
  EXPECT_NEAR(lone.slip_before, 1.0, 1e-12);  // u = 1 at every marker, V = 0
  EXPECT_NEAR(pair.slip_before, 1.0, 1e-12);
  // The row sums: a lone tiling about 1/2 (within the floor and below 1), two tilings in one
  // support about twice that and still at most ≈ 1 — no rows near 2.
  EXPECT_GT(lone_scaled.row_sum_min, 0.3);
  EXPECT_LT(lone_scaled.row_sum_max, 0.7);
  EXPECT_GT(pair_scaled.row_sum_max, 1.5 * lone_scaled.row_sum_max);
  EXPECT_LT(pair_scaled.row_sum_max, 1.2);
  // Unscaled, the passes converge in both (|1 − λ| < 1): no over-correction at the overlap.
  EXPECT_LT(lone.slip_after, 0.25);
  EXPECT_LT(pair.slip_after, lone.slip_after);
  // Scaled, the lone tiling's passes converge faster (its λ ≈ 1/2 taken to ≈ 1).
  EXPECT_LT(lone_scaled.slip_after, 0.5 * lone.slip_after);
  EXPECT_LT(pair_scaled.slip_after, 0.25);
}

TEST(RowSumScaling, WithoutItNoRowSumsAreKept) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  Markers m(kGrid);
  m.add_body(sphere_mesh(Vec3(24, 24, 24), 7.2, 3), "sphere", rigid_options());
  DirectForcing forcing(slabs, m, ForcingParameters{});
  grid::XFaceField u(slabs), fu(slabs);
  grid::YFaceField v(slabs), fv(slabs);
  grid::ZFaceField w(slabs), fw(slabs);
  u.fill(0), fu.fill(0), v.fill(0), fv.fill(0), w.fill(0), fw.fill(0);
  forcing.apply(0.01, {u, v, w}, {fu, fv, fw});
  EXPECT_TRUE(forcing.row_sums().empty());
}

}  // namespace
}  // namespace systole::ibm
