#include "solver/scene/fsei/coupled_heart.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/scene/fsei/blood.h"
#include "solver/scene/fsei/checkpoint.h"

namespace systole::scene::fsei {
namespace {

grid::Grid box_grid(const config::Scenario& s, const GridPoints& pts) {
  return grid::Grid({pts.nx - 1, pts.ny - 1, pts.nz - 1, s.fluid.box_x_mm / kDmMm, s.fluid.box_y_mm / kDmMm,
                     s.fluid.box_z_mm / kDmMm});
}

// The heart in its box (build_left_heart checks the fit), on a grid that resolves its valves.
geometry::LeftHeart heart_on_grid(const config::Scenario& s, const GridPoints& pts, const grid::Grid& g) {
  geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);
  check_grid_resolves_valves(s, pts, g, heart);
  return heart;
}

std::vector<Link> heart_markers(const config::Scenario& s, const geometry::LeftHeart& heart, ibm::Markers& markers) {
  return add_heart_markers(s, heart, markers);
}

coupling::FluidModuleOptions fluid_module_options(const config::Fsei& fs) {
  coupling::FluidModuleOptions o;
  o.time_scale_ms = kTimeScaleMs;
  o.carry_over_reference_cfl = fs.forcing_carry_over_reference_cfl;
  return o;
}

}  // namespace

Resume find_resume_point(const config::Scenario& s, const std::filesystem::path& checkpoint_root, double end_ms) {
  Resume r;
  if (checkpoint_root.empty()) return r;
  r.directory = CheckpointDirectory(checkpoint_root).resumable();
  if (!r.directory) return r;
  std::string stored;
  r.state = read_state_file(*r.directory / "state.h5", stored);
  check_fingerprint(*r.directory, stored, scenario_fingerprint(s));
  const double t_resumed = r.state.scalar("scene/time_ms");
  if (t_resumed > end_ms + 1e-9)
    throw InputError("the checkpoint in " + r.directory->string() + " is at t = " + std::to_string(t_resumed) +
                     " ms, past this run's end (fsei.end_time_ms or beats: " + std::to_string(end_ms) +
                     " ms); ask for a longer run or remove the checkpoint directory");
  return r;
}

void check_grid_resolves_valves(const config::Scenario& s, const GridPoints& pts, const grid::Grid& g,
                                const geometry::LeftHeart& heart) {
  const double h_mm = std::max({g.dx(), g.dy(), g.dz()}) * kDmMm;
  const double d_mm = 2 * heart.plane.aortic_radius_mm;
  if (d_mm >= kMinCellsAcrossAorticOrifice * h_mm) return;
  const double h_max = d_mm / kMinCellsAcrossAorticOrifice;
  std::ostringstream m;
  m << "fsei.resolution = \"" << s.fsei.resolution << "\" (" << pts.nx << " x " << pts.ny << " x " << pts.nz
    << " points) is too coarse for the valves: the aortic orifice (diameter " << d_mm << " mm) spans " << d_mm / h_mm
    << " cells of " << h_mm << " mm; at least " << kMinCellsAcrossAorticOrifice << " are needed (spacing <= " << h_max
    << " mm: at least " << static_cast<int>(std::ceil(s.fluid.box_x_mm / h_max)) + 1 << " x "
    << static_cast<int>(std::ceil(s.fluid.box_y_mm / h_max)) + 1 << " x "
    << static_cast<int>(std::ceil(s.fluid.box_z_mm / h_max)) + 1 << " points)";
  throw InputError(m.str());
}

CoupledHeart::CoupledHeart(const config::Scenario& scenario, const Resume& resume)
    : s(scenario),
      points(fsei_grid_points(s)),
      grid(box_grid(s, points)),
      heart(heart_on_grid(s, points, grid)),
      group(build_shells(s, heart)),
      aorta(s, group),
      markers(grid),
      links(heart_markers(s, heart, markers)),
      marker_z_at_rest(marker_z(markers)),
      slabs(fluid_slabs(s, grid, marker_z_at_rest)),
      fluid(slabs, fluid_parameters(s, heart)),
      aorta_initial_ml(start_aorta_at_ground_pressure(s, heart, grid, fluid)),
      forcing_parameters(fsei::forcing_parameters(s.fsei)),
      forcing(slabs, markers, forcing_parameters),
      fluid_module(fluid, markers, forcing, fluid_module_options(s.fsei)),
      tension(s, heart, group, resume.archive()),
      scales(output_scales(s, grid)) {}

}  // namespace systole::scene::fsei
