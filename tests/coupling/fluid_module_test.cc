// coupling::FluidModule (the fluid with its immersed bodies as a scheduler module, issue #9's
// foundation): sub-cycling through the scheduler equals the fluid stepped by hand, save/restore
// repeats an interval bitwise, body nodes written as inputs move the forcing, and the loads
// read through the module give Archimedes' force on a sphere in a fluid at rest under a uniform
// body force, to round-off against its closed form for the discrete surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include "solver/core/errors.h"
#include "solver/coupling/fluid_module.h"
#include "solver/coupling/scheduler.h"
#include "solver/ibm/shapes.h"

namespace systole::coupling {
namespace {
using ibm::Vec3;

// A 16^3 box of side 2 (periodic x, y; no-slip z walls), Re 100, a sphere of diameter 0.8 at
// the centre, the stream u = 1 at t = 0 (ours: small enough for a unit test).
struct ImmersedSphere {
  grid::Grid g{{16, 16, 16, 2.0, 2.0, 2.0}};
  grid::Slabs slabs{g, MPI_COMM_WORLD};
  fluid::FluidSolver fluid;
  ibm::Markers markers{g};
  int sphere = -1;
  std::unique_ptr<ibm::DirectForcing> forcing;
  std::unique_ptr<FluidModule> module;

  static fluid::FluidParameters parameters() {
    fluid::FluidParameters p;
    p.reynolds = 100;
    p.cfl = 0.3;
    p.max_dt = 0.05;
    return p;
  }
  explicit ImmersedSphere(bool stream, Vec3 g_force = Vec3::Zero(), bool rigid = true,
                          ibm::ForcingParameters forcing_parameters = {}, FluidModuleOptions mo = {},
                          fluid::FluidParameters fluid_parameters = parameters())
      : fluid(slabs, fluid_parameters) {
    ibm::BodyOptions o;
    o.mm_per_unit = 1.0;
    o.normals = ibm::ExpectedNormals::outward;
    o.rigid = rigid;
    sphere = markers.add_body(ibm::sphere_mesh(Vec3(1, 1, 1), 0.4, 2), "sphere", o);
    forcing = std::make_unique<ibm::DirectForcing>(slabs, markers, forcing_parameters);
    mo.uniform_force_density = g_force;
    module = std::make_unique<FluidModule>(fluid, markers, *forcing, mo);
    if (stream)
      fluid.set_velocity([](double, double, double) { return 1.0; }, [](double, double, double) { return 0.0; },
                         [](double, double, double) { return 0.0; });
  }
};

bool bitwise_equal(const fluid::FluidSolver& a, const fluid::FluidSolver& b) {
  const auto& ua = a.velocity();
  const auto& ub = b.velocity();
  return std::memcmp(ua.u.data(), ub.u.data(), ua.u.bytes()) == 0 &&
         std::memcmp(ua.v.data(), ub.v.data(), ua.v.bytes()) == 0 &&
         std::memcmp(ua.w.data(), ub.w.data(), ua.w.bytes()) == 0 &&
         std::memcmp(a.pressure().data(), b.pressure().data(), a.pressure().bytes()) == 0 && a.time() == b.time();
}

TEST(FluidModule, SubCyclesUnderTheSchedulerAsTheFluidSteppedByHand) {
  ImmersedSphere a(true), b(true);
  const double sync_ms = 4 * a.module->max_step_ms();  // about four fluid steps per interval
  SchedulerOptions so;
  so.sync_step_ms = sync_ms;
  std::vector<Stage> stages(1);
  stages[0].module = a.module.get();
  Scheduler s(std::move(stages), so);
  s.advance_to(5 * sync_ms);
  // By hand, on the twin: the scheduler's rule (what is left of the interval split evenly into
  // substeps no larger than the fluid's stable step), each substep one fluid step.
  const double scale = 40.0;  // the module's default d_m/U_m in ms
  for (int interval = 1; interval <= 5; ++interval) {
    const double t_end_ms = interval * sync_ms;
    while (t_end_ms - b.fluid.time() * scale > 1e-12 * t_end_ms) {
      const double left = t_end_ms - b.fluid.time() * scale;
      const double substeps = std::ceil(left / (b.fluid.stable_step() * scale) * (1 - 1e-12));
      const double dt_ms = substeps <= 1 ? left : left / substeps;
      b.fluid.advance(b.fluid.time() + dt_ms / scale);
    }
  }
  const ModuleStats& st = s.stats().modules.at(0);
  std::printf("  [measured] %lld fluid steps in %lld intervals, steps %.4g-%.4g ms, max step/limit %.6f\n",
              st.steps, s.stats().intervals, st.min_step_ms, st.max_step_ms, st.max_step_over_limit);
  EXPECT_EQ(st.name, "fluid");
  EXPECT_GT(st.steps, s.stats().intervals);  // sub-cycled
  EXPECT_LE(st.max_step_over_limit, 1 + 1e-12);
  EXPECT_NEAR(a.module->time_ms(), 5 * sync_ms, 1e-9 * sync_ms);
  EXPECT_EQ(a.fluid.steps(), b.fluid.steps());
  EXPECT_TRUE(bitwise_equal(a.fluid, b.fluid));
  EXPECT_GT(a.module->last_forcing().slip_before.markers, 0u);  // the forcing ran in the hook
}

// The carry-over forcing starts each step from the last step's force: that force is state, so
// restore() must bring it back too (else a strong coupling's repeated interval is not a fixed-
// point iteration and a restored run drifts).
class FluidModuleRestore : public ::testing::TestWithParam<bool> {};

TEST_P(FluidModuleRestore, RepeatsAnIntervalBitwise) {
  ibm::ForcingParameters fp;
  fp.carry_over = GetParam();
  ImmersedSphere a(true, Vec3::Zero(), true, fp);
  for (int n = 0; n < 3; ++n) a.module->step(a.module->max_step_ms());
  a.module->save();
  const double t0 = a.module->time_ms();
  for (int n = 0; n < 4; ++n) a.module->step(a.module->max_step_ms());
  const fluid::Velocity first = a.fluid.velocity();
  const grid::CellField first_p = a.fluid.pressure();
  const double t1 = a.module->time_ms();
  a.module->restore();
  EXPECT_EQ(a.module->time_ms(), t0);
  for (int n = 0; n < 4; ++n) a.module->step(a.module->max_step_ms());
  EXPECT_EQ(a.module->time_ms(), t1);
  EXPECT_EQ(std::memcmp(first.u.data(), a.fluid.velocity().u.data(), first.u.bytes()), 0);
  EXPECT_EQ(std::memcmp(first.w.data(), a.fluid.velocity().w.data(), first.w.bytes()), 0);
  EXPECT_EQ(std::memcmp(first_p.data(), a.fluid.pressure().data(), first_p.bytes()), 0);
  if (GetParam()) {
    EXPECT_FALSE(a.forcing->carried_force().empty());
  }
}
INSTANTIATE_TEST_SUITE_P(CarryOver, FluidModuleRestore, ::testing::Bool(),
                         [](const auto& info) { return info.param ? "carried_force" : "seed_forcing"; });

// The carry-over's step-aware increment share (FluidModuleOptions::carry_over_reference_cfl):
// at CFL 0.2 with the reference CFL 0.4 every CFL-limited step keeps w = 0.5 of its corrections,
// so the run equals, bitwise, the one with the forcing's fixed share 0.5, and differs from the
// plain carry-over; where max_dt sets both steps it is the plain carry-over, bitwise.
TEST(FluidModule, TheReferenceCflSharesTheIncrementsByTheStepRatio) {
  ibm::ForcingParameters carry;
  carry.carry_over = true;
  carry.iterations = 3;
  ibm::ForcingParameters half = carry;
  half.carry_over_increment_share = 0.5;
  FluidModuleOptions ref;
  ref.carry_over_reference_cfl = 0.4;
  auto run = [](fluid::FluidParameters p, ibm::ForcingParameters f, FluidModuleOptions o) {
    auto s = std::make_unique<ImmersedSphere>(true, Vec3::Zero(), true, f, o, p);
    for (int n = 0; n < 6; ++n) s->module->step(s->module->max_step_ms());
    return s;
  };
  fluid::FluidParameters cfl_limited = ImmersedSphere::parameters();
  cfl_limited.cfl = 0.2;  // the stream's CFL step at 0.4 is max_dt 0.05, then below it
  const auto a = run(cfl_limited, carry, ref), b = run(cfl_limited, half, {}), c = run(cfl_limited, carry, {});
  ASSERT_LT(a->fluid.step_at_cfl(0.4), cfl_limited.max_dt);  // CFL-limited at both targets
  EXPECT_TRUE(bitwise_equal(a->fluid, b->fluid));
  EXPECT_EQ(a->forcing->carried_force(), b->forcing->carried_force());
  EXPECT_FALSE(bitwise_equal(a->fluid, c->fluid));
  EXPECT_NE(a->forcing->carried_force(), c->forcing->carried_force());

  fluid::FluidParameters capped = cfl_limited;
  capped.max_dt = 0.005;  // below the CFL step at 0.2 (≈ 0.02): both steps are max_dt
  const auto d = run(capped, carry, ref), e = run(capped, carry, {});
  ASSERT_EQ(d->fluid.step_at_cfl(0.2), capped.max_dt);
  EXPECT_TRUE(bitwise_equal(d->fluid, e->fluid));
  EXPECT_EQ(d->forcing->carried_force(), e->forcing->carried_force());
}

TEST(FluidModule, AReferenceCflOutsideZeroToOneIsAnInputError) {
  ImmersedSphere a(false);
  for (double bad : {-0.1, 1.2}) {
    FluidModuleOptions o;
    o.carry_over_reference_cfl = bad;
    try {
      FluidModule m(a.fluid, a.markers, *a.forcing, o);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("carry_over_reference_cfl = "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("[0, 1]"), std::string::npos) << e.what();
    }
  }
}

TEST(FluidModule, BodyNodesWrittenAsInputsMoveTheForcing) {
  // A deformable sphere in fluid at rest, given the velocity (0.5, 0, 0) at every node: after
  // one step the fluid at the markers follows it (the slip the forcing saw was the full 0.5),
  // and the force on the fluid points along +x.
  ImmersedSphere a(false, Vec3::Zero(), /*rigid=*/false);
  const ibm::Body& body = a.markers.bodies().at(a.sphere);
  const std::vector<Vec3> x = body.tiled.position_mm;  // grid units (markers.h)
  a.module->set_body_nodes(a.sphere, x, std::vector<Vec3>(x.size(), Vec3(0.5, 0, 0)));
  a.module->step(a.module->max_step_ms());
  const ibm::ForcingReport& r = a.module->last_forcing();
  std::printf("  [measured] slip before %.4f (rms), force on the fluid (%.4g, %.3g, %.3g)\n", r.slip_before.rms,
              r.total_force.x(), r.total_force.y(), r.total_force.z());
  EXPECT_NEAR(r.slip_before.rms, 0.5, 1e-12);
  EXPECT_GT(r.total_force.x(), 0);
  EXPECT_LT(std::abs(r.total_force.y()) + std::abs(r.total_force.z()), 1e-6 * r.total_force.x());
}

TEST(FluidModule, LoadsGiveArchimedesForceInAFluidAtRest) {
  // Fluid at rest under g = (0, 0, 1.5) with the hydrostatic p = 1.5 (z − 1). Eq 14
  // takes p at the probe X + h n (no body-force term), so the discrete closed form of the load
  // is F = −g Σ_b (z_b + h n_z,b) n_b A_b = −g (V + h Σ n_z,b² A_b) ẑ, V the enclosed volume of
  // the triangles (Σ z n A, exact for flat tiles with centroid quadrature).
  const Vec3 g(0, 0, 1.5);
  ImmersedSphere a(false, g);
  // Start from the hydrostatic pressure: with AB2's α = 1 the predictor's −Δt∇p cancels Δt g,
  // the markers see no slip and the fluid stays at rest to round-off.
  a.fluid.set_pressure([&](double, double, double z) { return g.z() * (z - 1.0); });
  for (int n = 0; n < 20; ++n) a.module->step(a.module->max_step_ms());
  const ibm::MarkerLoads L = a.module->loads();
  const auto& m = a.markers.markers();
  double volume = 0, probe_term = 0;
  for (std::size_t b = 0; b < a.markers.size(); ++b) {
    volume += m.surface[b].z() * m.normal[b].z() * m.area[b];
    probe_term += a.markers.h() * m.normal[b].z() * m.normal[b].z() * m.area[b];
  }
  const double expected = -g.z() * (volume + probe_term);
  const double speed = a.fluid.diagnostics().max_speed;
  std::printf("  [measured] F = (%.3g, %.3g, %.10f), closed form %.10f (V %.6f, exact sphere %.6f), max |u| %.2g\n",
              L.total_force.x(), L.total_force.y(), L.total_force.z(), expected, volume, 4.0 / 3 * M_PI * 0.064,
              speed);
  EXPECT_LT(speed, 1e-10);
  EXPECT_NEAR(L.total_force.z(), expected, 1e-8 * std::abs(expected));
  EXPECT_LT(std::hypot(L.total_force.x(), L.total_force.y()), 1e-8 * std::abs(expected));
}

TEST(FluidModule, NonPositiveTimeScaleIsAnInputError) {
  ImmersedSphere a(false);
  FluidModuleOptions o;
  o.time_scale_ms = 0;
  try {
    FluidModule bad(a.fluid, a.markers, *a.forcing, o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("time_scale_ms"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace systole::coupling
