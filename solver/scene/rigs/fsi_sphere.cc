#include "solver/scene/rigs/fsi_sphere.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/coupling/fluid_module.h"
#include "solver/coupling/scheduler.h"
#include "solver/coupling/shell_module.h"
#include "solver/geometry/tiling.h"
#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"

namespace systole::scene {
namespace {
using geometry::Vec3;

constexpr double kDmMm = 24.0;                                                  // d_m (seed)
constexpr double kUmMmPerMs = 0.6;                                              // U_m (seed)
constexpr double kTimeScaleMs = kDmMm / kUmMmPerMs;                             // 40 ms
constexpr double kForceScaleMn = 1.05 * kUmMmPerMs * kUmMmPerMs * kDmMm * kDmMm;  // ρU²d² = 217.7 mN
constexpr double kBoxMm = 48.0;
const Vec3 kCentreMm(24, 24, 24);

void check(const FsiSphereOptions& o) {
  auto bad = [](const std::string& field, double value, const std::string& allowed) {
    std::ostringstream m;
    m << "fsi_sphere." << field << " = " << value << " is out of range " << allowed;
    throw InputError(m.str());
  };
  if (o.cells < 8 || o.cells > 256) bad("cells", o.cells, "[8, 256]");
  if (!(o.reynolds > 0)) bad("reynolds", o.reynolds, "(0, inf)");
  if (!(o.stretch >= 1 && o.stretch <= 1.5)) bad("stretch", o.stretch, "[1, 1.5]");
  // The stretched sphere stays 0.1 box from the walls (its markers' supports inside the box).
  if (!(o.radius_mm > 0 && o.stretch * o.radius_mm <= 0.4 * kBoxMm))
    bad("radius_mm", o.radius_mm, "(0, " + std::to_string(0.4 * kBoxMm / o.stretch) + "] mm (19.2 mm / stretch)");
  if (o.icosphere_level < 1 || o.icosphere_level > 6) bad("icosphere_level", o.icosphere_level, "[1, 6]");
  if (!(o.thickness_mm > 0)) bad("thickness_mm", o.thickness_mm, "(0, inf)");
  if (!(o.stiffness_scale > 0)) bad("stiffness_scale", o.stiffness_scale, "(0, inf)");
  if (o.strong_passes < 1) bad("strong_passes", o.strong_passes, "[1, inf)");
  if (!(o.sync_step_ms > 0)) bad("sync_step_ms", o.sync_step_ms, "(0, inf)");
  if (!(o.end_ms > 0)) bad("end_ms", o.end_ms, "(0, inf)");
  if (!(o.sample_ms > 0)) bad("sample_ms", o.sample_ms, "(0, inf)");
}

geometry::TriMesh rest_sphere(const FsiSphereOptions& o) {
  geometry::TriMesh rest =
      structure::icosphere(o.radius_mm, o.icosphere_level, o.thickness_mm, geometry::Tissue::kLvMyocardium, false);
  for (auto& p : rest.position_mm) p += kCentreMm;
  return rest;
}

std::unique_ptr<structure::ShellModel> stretched_shell(const FsiSphereOptions& o) {
  structure::ShellMaterials m;
  for (auto& t : m.tissue) t = {13.3e-3 * o.stiffness_scale, 49.56, 49.56};  // seed LV c, α_f; isotropic
  m.density_mg_per_mm3 = 1.05;
  m.poisson_ratio = 0.5;
  structure::ShellOptions so;
  so.law = "fung";
  so.bending = false;
  auto shell = std::make_unique<structure::ShellModel>(rest_sphere(o), m, so);
  std::vector<Vec3> x = shell->positions_mm();
  for (auto& p : x) p = kCentreMm + o.stretch * (p - kCentreMm);
  shell->set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  return shell;
}

}  // namespace

DrySphereResult run_dry_sphere(const FsiSphereOptions& o, double stop_at_loss) {
  check(o);
  auto dry = stretched_shell(o);
  const double v0 = dry->cavity_volume_mm3();
  DrySphereResult r;
  while (dry->time_ms() < o.end_ms && r.min_volume_ratio > 1 - stop_at_loss) {
    dry->advance(o.sync_step_ms);
    r.min_volume_ratio = std::min(r.min_volume_ratio, dry->cavity_volume_mm3() / v0);
    r.time_ms = dry->time_ms();
  }
  return r;
}

FsiSphereResult run_fsi_sphere(const FsiSphereOptions& o, MPI_Comm comm) {
  check(o);
  auto shell = stretched_shell(o);
  FsiSphereResult res;
  res.initial_volume_mm3 = shell->cavity_volume_mm3();
  const grid::Grid g({o.cells, o.cells, o.cells, kBoxMm / kDmMm, kBoxMm / kDmMm, kBoxMm / kDmMm});
  const grid::Slabs slabs(g, comm);
  fluid::FluidParameters fp;
  fp.reynolds = o.reynolds;
  fp.max_dt = o.sync_step_ms / kTimeScaleMs;
  fluid::FluidSolver fluid(slabs, fp);
  ibm::Markers markers(g);
  ibm::BodyOptions bo;
  bo.mm_per_unit = kDmMm;
  bo.normals = ibm::ExpectedNormals::inward;  // a chamber: the blood inside (icosphere convention)
  bo.rigid = false;
  bo.spacing_fraction = o.marker_spacing_fraction;
  bo.retraction_cells = o.marker_retraction_cells;
  geometry::TriMesh current = rest_sphere(o);
  current.position_mm = shell->positions_mm();
  const int body = markers.add_body(current, "sphere", bo);
  const geometry::TilingMap map = geometry::tiling_map(current, markers.bodies()[body].tiling_level);
  ibm::ForcingParameters fpar;
  fpar.carry_over = o.carry_over;
  fpar.carry_over_factor = o.carry_over_factor;
  fpar.iterations = o.forcing_iterations;
  fpar.kernel = o.divergence_free_kernel ? ibm::TransferKernel::divergence_free : ibm::TransferKernel::mls;
  ibm::DirectForcing forcing(slabs, markers, fpar);
  coupling::FluidModule fm(fluid, markers, forcing, coupling::FluidModuleOptions{});
  coupling::ShellModule sm(*shell);

  coupling::Transfer loads{"loads on the membrane",
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
  coupling::Transfer nodes{"membrane nodes to the markers",
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
  std::vector<coupling::Stage> stages(2);
  stages[0].module = &fm;
  stages[0].after = {loads};
  stages[1].module = &sm;
  stages[1].after = {nodes};
  coupling::SchedulerOptions so;
  so.sync_step_ms = o.sync_step_ms;
  so.mode = o.strong_coupling ? coupling::CouplingMode::strong : coupling::CouplingMode::loose;
  so.strong_max_iterations = o.strong_passes;
  coupling::Scheduler s(std::move(stages), so);
  const double mm3_per_ms_per_unit = kDmMm * kDmMm * kUmMmPerMs;  // U d² in mm³/ms
  auto out_fluxes = [&] {  // {slip, told}; collective
    const fluid::Velocity& u = fluid.velocity();
    const std::vector<Vec3> ub = forcing.transfer().interpolate(ibm::ConstVelocityView{u.u, u.v, u.w});
    const ibm::MarkerArrays& ma = markers.markers();
    double slip = 0, told = 0;
    for (std::size_t mk = 0; mk < ma.size(); ++mk) {
      slip -= (ub[mk] - ma.velocity[mk]).dot(ma.normal[mk]) * ma.area[mk];
      told -= ma.velocity[mk].dot(ma.normal[mk]) * ma.area[mk];
    }
    return std::pair{slip * mm3_per_ms_per_unit, told * mm3_per_ms_per_unit};
  };
  try {
    double t_before = 0, slip_before = 0, told_before = 0;
    for (double t = o.sample_ms; t <= o.end_ms * (1 + 1e-12); t += o.sample_ms) {
      s.advance_to(t);
      const double ratio = shell->cavity_volume_mm3() / res.initial_volume_mm3;
      const auto [slip, told] = out_fluxes();
      res.slip_volume_mm3 += 0.5 * (t - t_before) * (slip + slip_before);
      res.told_volume_mm3 += 0.5 * (t - t_before) * (told + told_before);
      t_before = t;
      slip_before = slip;
      told_before = told;
      res.time_ms.push_back(t);
      res.volume_ratio.push_back(ratio);
      res.min_volume_ratio = std::min(res.min_volume_ratio, ratio);
      res.max_volume_ratio = std::max(res.max_volume_ratio, ratio);
    }
    const ibm::MarkerLoads L = fm.loads();
    double p = 0, area = 0;
    for (std::size_t b = 0; b < markers.size(); ++b) {
      p += L.wall_pressure[b] * markers.markers().area[b];
      area += markers.markers().area[b];
    }
    res.mean_wall_pressure = p / area;
  } catch (const InstabilityError& e) {
    res.stopped = e.what();
  }
  const auto& st = s.stats();
  res.fluid_steps = st.modules[0].steps;
  res.shell_substeps = st.modules[1].steps;
  res.passes = st.passes;
  res.unconverged_intervals = st.unconverged_intervals;
  res.max_step_over_limit = std::max(st.modules[0].max_step_over_limit, st.modules[1].max_step_over_limit);
  return res;
}

}  // namespace systole::scene
