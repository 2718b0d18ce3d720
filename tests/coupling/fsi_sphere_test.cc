// Fluid–structure coupling of issue #9 on the smallest case that has both (solver/scene/rigs/fsi_sphere.h):
// a closed elastic membrane pre-stretched by 10 % and released at rest in blood at rest, fluid +
// immersed boundary + shell through the scheduler. The enclosed blood is incompressible, so the
// membrane cannot shrink back to its rest size: its volume must stay close to the initial one,
// while the same membrane without fluid loses 15 % within milliseconds. With the seed's
// direct forcing (one pass) the membrane leaks 21 % of its volume in 60 ms; with the carry-over
// forcing (ours, docs/ibm.md) 2 % at Δt_sync = 0.1 ms (9 % at 0.5 ms: docs/fsei.md).
#include <gtest/gtest.h>

#include <cstdio>

#include "solver/core/errors.h"
#include "solver/scene/rigs/fsi_sphere.h"

namespace systole::scene {
namespace {

TEST(FsiSphere, EnclosedBloodHoldsAStretchedMembraneThatCollapsesWithout) {
  const FsiSphereOptions o;  // 32^3, Re 3000, loose coupling at 0.1 ms, carry-over forcing, 60 ms
  const DrySphereResult dry = run_dry_sphere(o, 0.15);
  const FsiSphereResult wet = run_fsi_sphere(o, MPI_COMM_WORLD);
  for (std::size_t k = 0; k < wet.time_ms.size(); ++k)
    std::printf("  t %.0f ms: V/V0 %.4f\n", wet.time_ms[k], wet.volume_ratio[k]);
  std::printf("  [measured] V0 %.1f mm^3; dry %.3f at %.1f ms; wet min / max %.4f / %.4f; fluid steps %lld, shell "
              "substeps %lld; mean wall pressure %.4g (rho U^2)%s%s\n",
              wet.initial_volume_mm3, dry.min_volume_ratio, dry.time_ms, wet.min_volume_ratio, wet.max_volume_ratio,
              wet.fluid_steps, wet.shell_substeps, wet.mean_wall_pressure, wet.stopped.empty() ? "" : "; stopped: ",
              wet.stopped.c_str());
  ASSERT_TRUE(wet.stopped.empty()) << wet.stopped;
  EXPECT_LE(dry.min_volume_ratio, 0.85);  // without blood the membrane shrinks towards rest
  // With it, the enclosed volume holds, up to the diffuse interface's leak: measured (2026-12-01)
  // V/V0 falling smoothly to 0.979 at 60 ms (0.965 at 200 ms, levelling off; docs/fsei.md).
  // The bound guards that measurement; it is not a physical tolerance.
  EXPECT_GT(wet.min_volume_ratio, 0.97);
  EXPECT_LT(wet.max_volume_ratio, 1.0 + 1e-9);
  EXPECT_LE(wet.max_step_over_limit, 1 + 1e-12);
}

// The divergence-free kernel (ibm::TransferKernel::divergence_free, ours): with MLS the forcing
// holds the interpolated velocity at the wall's (the slip at the markers is 4 % of the volume
// lost with the carry-over) while the membrane still shrinks through the blood, since the MLS
// interpolant of a divergence-free grid field has a net flux through a closed surface; with the
// composite B-splines that flux vanishes, and what the membrane loses is exactly the slip the
// forcing leaves at the markers. Measured (2026-12-02, 40 ms, carry-over, one pass): 1.12 % lost
// with MLS (slip 0.04 % of V0), 0.015 % with the kernel (slip 0.014 %); docs/fsei.md, session 14.
TEST(FsiSphere, TheDivergenceFreeKernelHoldsTheVolumeTheMlsKernelLoses) {
  FsiSphereResult r[2];
  for (int k = 0; k < 2; ++k) {
    FsiSphereOptions o;
    o.end_ms = 40;
    o.sample_ms = 0.1;  // every synchronisation: the slip's integral
    o.divergence_free_kernel = k == 1;
    r[k] = run_fsi_sphere(o, MPI_COMM_WORLD);
    ASSERT_TRUE(r[k].stopped.empty()) << r[k].stopped;
    std::printf("  [measured] %s: V/V0 %.5f at 40 ms; lost %.4g mm^3, slip through the markers %.4g mm^3, swept by "
                "the markers' velocities %.4g mm^3\n",
                k ? "divergence-free kernel" : "MLS", r[k].volume_ratio.back(),
                r[k].initial_volume_mm3 * (1 - r[k].volume_ratio.back()), r[k].slip_volume_mm3, r[k].told_volume_mm3);
  }
  const double lost_mls = r[0].initial_volume_mm3 * (1 - r[0].volume_ratio.back());
  const double lost_df = r[1].initial_volume_mm3 * (1 - r[1].volume_ratio.back());
  // The markers' velocities sweep what the shell loses (the coupling hands the shell's motion to
  // the fluid faithfully) with either kernel.
  for (int k = 0; k < 2; ++k) {
    const double lost = r[k].initial_volume_mm3 * (1 - r[k].volume_ratio.back());
    EXPECT_NEAR(-r[k].told_volume_mm3, lost, 0.05 * std::abs(lost) + 0.05);
  }
  EXPECT_LT(lost_df, 0.1 * lost_mls);
  EXPECT_LT(lost_df, 1e-3 * r[1].initial_volume_mm3);
  // MLS: the slip seen at the markers is a small part of the loss; the kernel: nearly all of it.
  EXPECT_LT(r[0].slip_volume_mm3, 0.2 * lost_mls);
  EXPECT_NEAR(r[1].slip_volume_mm3, lost_df, 0.25 * lost_df);
}

// The carry-over factor β (ibm::ForcingParameters::carry_over_factor) sits between no carry-over
// and a full one: the leak grows as less of the previous force is carried (the heart's forcing,
// 3 iterations). Measured (2026-12-02, 60 ms): V/V0 0.9865 (β = 1), 0.9650 (0.9), 0.9116 (off).
TEST(FsiSphere, APartialCarryOverLeaksBetweenNoneAndAFullOne) {
  double lowest[3];
  const double factors[3] = {1.0, 0.9, 0.0};  // 0: no carry-over
  for (int k = 0; k < 3; ++k) {
    FsiSphereOptions o;
    o.forcing_iterations = 3;
    o.carry_over = factors[k] > 0;
    if (o.carry_over) o.carry_over_factor = factors[k];
    const FsiSphereResult r = run_fsi_sphere(o, MPI_COMM_WORLD);
    ASSERT_TRUE(r.stopped.empty()) << r.stopped;
    lowest[k] = r.min_volume_ratio;
    std::printf("  [measured] carry-over factor %.1f: V/V0 lowest %.4f in 60 ms\n", factors[k], lowest[k]);
  }
  EXPECT_GT(lowest[0], lowest[1]);
  EXPECT_GT(lowest[1], lowest[2]);
  // out of (0, 1]: named
  FsiSphereOptions bad;
  bad.carry_over_factor = 1.5;
  try {
    run_fsi_sphere(bad, MPI_COMM_WORLD);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("carry-over factor = 1.5"), std::string::npos) << e.what();
  }
}

TEST(FsiSphere, BadOptionIsAnInputErrorNamingIt) {
  FsiSphereOptions o;
  o.stretch = 2;
  try {
    run_fsi_sphere(o, MPI_COMM_WORLD);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("fsi_sphere.stretch"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace systole::scene
