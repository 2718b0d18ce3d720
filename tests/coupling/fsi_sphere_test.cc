// Fluid–structure coupling of issue #9 on the smallest case that has both: a closed elastic
// membrane (structure::ShellModel, an icosphere) pre-stretched by 10 % and released in blood at
// rest, coupled through the scheduler with coupling::FluidModule (MLS direct forcing, loads of
// eq 11–14 from the inside, as for a chamber) and geometry::tiling_map between the shell's nodes
// and the markers' tiled nodes. The enclosed blood is incompressible, so the membrane cannot
// shrink back to its rest size: its volume must stay close to the initial one while the same
// membrane without fluid loses 15 % within 2 ms; the blood's pressure then holds the tension.
// With the seed's direct forcing (one pass) the membrane leaked 25 % of its volume in 60 ms;
// with the carry-over forcing (ours, docs/ibm.md) about 9 %: the leak is the measured weak point.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "solver/coupling/fluid_module.h"
#include "solver/coupling/scheduler.h"
#include "solver/coupling/shell_module.h"
#include "solver/geometry/tiling.h"
#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"

namespace systole::coupling {
namespace {
using geometry::Vec3;

constexpr double kDmMm = 24.0;                                  // d_m (seed)
constexpr double kUmMmPerMs = 0.6;                              // U_m (seed)
constexpr double kTimeScaleMs = kDmMm / kUmMmPerMs;             // 40 ms
constexpr double kForceScaleMn = 1.05 * kUmMmPerMs * kUmMmPerMs * kDmMm * kDmMm;  // ρU²d² = 217.7 mN
constexpr double kStretch = 1.1;
constexpr double kRadiusMm = 10.0;
const Vec3 kCentreMm(24, 24, 24);

structure::ShellMaterials materials() {
  structure::ShellMaterials m;
  for (auto& t : m.tissue) t = {13.3e-3 * 20, 49.56, 49.56};  // the seed's LV c ×20, isotropic (ours)
  m.density_mg_per_mm3 = 1.05;
  m.poisson_ratio = 0.5;
  return m;
}

std::unique_ptr<structure::ShellModel> stretched_sphere() {
  geometry::TriMesh rest = structure::icosphere(kRadiusMm, 3, 2.0, geometry::Tissue::kLvMyocardium, false);
  for (auto& p : rest.position_mm) p += kCentreMm;
  structure::ShellOptions o;
  o.law = "fung";
  o.bending = false;
  auto shell = std::make_unique<structure::ShellModel>(rest, materials(), o);
  std::vector<Vec3> x = shell->positions_mm();
  for (auto& p : x) p = kCentreMm + kStretch * (p - kCentreMm);
  shell->set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  return shell;
}

TEST(FsiSphere, EnclosedBloodHoldsAStretchedMembraneThatCollapsesWithout) {
  const double t_end_ms = 60;
  // Dry: the same membrane alone.
  auto dry = stretched_sphere();
  const double v0 = dry->cavity_volume_mm3();
  double dry_min = v0;
  double dry_time_ms = 0;  // when it had lost 15 % (it goes on into compression and crumples)
  while (dry->time_ms() < t_end_ms && dry_min > 0.85 * v0) {
    dry->advance(0.5);
    dry_min = std::min(dry_min, dry->cavity_volume_mm3());
    dry_time_ms = dry->time_ms();
  }

  // Wet: in a 48 mm periodic box of blood at rest (32^3 cells, h = 1.5 mm), Re 3000 (seed).
  auto shell = stretched_sphere();
  const grid::Grid g({32, 32, 32, 2.0, 2.0, 2.0});
  const grid::Slabs slabs(g, MPI_COMM_WORLD);
  fluid::FluidParameters fp;
  fp.reynolds = 3000;
  fp.max_dt = 0.5 / kTimeScaleMs;
  fluid::FluidSolver fluid(slabs, fp);
  ibm::Markers markers(g);
  ibm::BodyOptions bo;
  bo.mm_per_unit = kDmMm;
  bo.normals = ibm::ExpectedNormals::inward;  // a chamber: blood inside (icosphere convention)
  bo.rigid = false;
  geometry::TriMesh current = structure::icosphere(kRadiusMm, 3, 2.0, geometry::Tissue::kLvMyocardium, false);
  current.position_mm = shell->positions_mm();
  const int body = markers.add_body(current, "sphere", bo);
  const geometry::TilingMap map = geometry::tiling_map(current, markers.bodies()[body].tiling_level);
  ibm::ForcingParameters fpar;
  fpar.carry_over = true;  // stops the leak of a membrane under a pressure jump (docs/ibm.md)
  ibm::DirectForcing forcing(slabs, markers, fpar);
  FluidModule fm(fluid, markers, forcing, FluidModuleOptions{});
  ShellModule sm(*shell);

  Transfer loads{"loads on the membrane",
                 [&](std::vector<double>& d) {
                   const ibm::MarkerLoads L = fm.loads();
                   const std::vector<Vec3> f = map.spread(L.nodal_force.at(body), shell->node_count());
                   d.resize(3 * f.size());
                   for (std::size_t n = 0; n < f.size(); ++n)
                     for (int c = 0; c < 3; ++c) d[3 * n + c] = kForceScaleMn * f[n][c];
                 },
                 [&](const std::vector<double>& d) {
                   std::vector<Vec3> f(d.size() / 3);
                   for (std::size_t n = 0; n < f.size(); ++n) f[n] = Vec3(d[3 * n], d[3 * n + 1], d[3 * n + 2]);
                   shell->set_external_loads(std::move(f));
                 },
                 true};
  Transfer nodes{"membrane nodes to the markers",
                 [&](std::vector<double>& d) {
                   const auto x = map.interpolate(shell->positions_mm());
                   const auto v = map.interpolate(shell->velocities_mm_per_ms());
                   d.resize(6 * x.size());
                   for (std::size_t n = 0; n < x.size(); ++n)
                     for (int c = 0; c < 3; ++c) {
                       d[6 * n + c] = x[n][c] / kDmMm;
                       d[6 * n + 3 + c] = v[n][c] / kUmMmPerMs;
                     }
                 },
                 [&](const std::vector<double>& d) {
                   std::vector<Vec3> x(d.size() / 6), v(d.size() / 6);
                   for (std::size_t n = 0; n < x.size(); ++n) {
                     x[n] = Vec3(d[6 * n], d[6 * n + 1], d[6 * n + 2]);
                     v[n] = Vec3(d[6 * n + 3], d[6 * n + 4], d[6 * n + 5]);
                   }
                   fm.set_body_nodes(body, x, v);
                 },
                 false};
  std::vector<Stage> stages(2);
  stages[0].module = &fm;
  stages[0].after = {loads};
  stages[1].module = &sm;
  stages[1].after = {nodes};
  SchedulerOptions so;
  so.sync_step_ms = 0.5;
  so.mode = CouplingMode::loose;  // the seed's production coupling
  Scheduler s(std::move(stages), so);
  double wet_min = v0, wet_max = v0;
  for (double t = 5; t <= t_end_ms + 1e-9; t += 5) {
    s.advance_to(t);
    const double v = shell->cavity_volume_mm3();
    wet_min = std::min(wet_min, v);
    wet_max = std::max(wet_max, v);
    std::printf("  t %.0f ms: V/V0 %.4f\n", t, v / v0);
  }
  // The blood's pressure on the membrane: the mean of eq 14's wall pressure inside, against
  // the membrane's own inward pull per area (its elastic force, spread over the area).
  const ibm::MarkerLoads L = fm.loads();
  double p_mean = 0, area = 0;
  for (std::size_t b = 0; b < markers.size(); ++b) {
    p_mean += L.wall_pressure[b] * markers.markers().area[b];
    area += markers.markers().area[b];
  }
  std::printf("  [measured] V0 %.1f mm^3; dry %.1f (%.1f %%) at %.1f ms; wet min / max %.1f / %.1f (%.2f / %.2f %%); "
              "fluid steps %lld, shell substeps %lld; mean wall pressure %.4g (rho U^2)\n",
              v0, dry_min, 100 * (dry_min / v0 - 1), dry_time_ms, wet_min, wet_max, 100 * (wet_min / v0 - 1),
              100 * (wet_max / v0 - 1), s.stats().modules[0].steps, s.stats().modules[1].steps, p_mean / area);
  EXPECT_LE(dry_min / v0, 0.85);              // without blood the membrane shrinks towards rest
  // With it, the enclosed volume holds, up to the diffuse interface's leak: measured (2026-12-01)
  // V/V0 oscillating between 0.93 and 0.98 and drifting down to 0.91 at 60 ms (docs/fsei.md).
  // The bound guards that measurement; it is not a physical tolerance.
  EXPECT_GT(wet_min / v0, 0.88);
  EXPECT_LT(wet_max / v0, 1.0 + 1e-9);
  EXPECT_LE(s.stats().modules[0].max_step_over_limit, 1 + 1e-12);
  EXPECT_LE(s.stats().modules[1].max_step_over_limit, 1 + 1e-12);
}

}  // namespace
}  // namespace systole::coupling
