#include "solver/scene/fsei/coupled_heart.h"

#include "solver/core/errors.h"
#include "solver/scene/fsei/blood.h"
#include "solver/scene/fsei/checkpoint.h"

namespace systole::scene::fsei {
namespace {

grid::Grid box_grid(const config::Scenario& s, const GridPoints& pts) {
  return grid::Grid({pts.nx - 1, pts.ny - 1, pts.nz - 1, s.fluid.box_x_mm / kDmMm, s.fluid.box_y_mm / kDmMm,
                     s.fluid.box_z_mm / kDmMm});
}

std::vector<Link> heart_markers(const config::Scenario& s, const geometry::LeftHeart& heart, ibm::Markers& markers) {
  return add_heart_markers(s, heart, markers);
}

coupling::FluidModuleOptions fluid_module_options(const config::Fsei& fs) {
  coupling::FluidModuleOptions o;
  o.time_scale_ms = kTimeScaleMs;
  o.carry_over_reference_cfl = fs.forcing.carry_over_reference_cfl;
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

CoupledHeart::CoupledHeart(const config::Scenario& scenario, const Resume& resume)
    : s(scenario),
      points(fsei_grid_points(s)),
      grid(box_grid(s, points)),
      heart(geometry::build_left_heart(s.geometry, s.fluid)),  // checks the fit in the box
      group(build_shells(s, heart)),
      aorta(s, group),
      markers(grid),
      links(heart_markers(s, heart, markers)),
      marker_z_at_rest(marker_z(markers)),
      slabs(fluid_slabs(s, grid, marker_z_at_rest)),
      fluid(slabs, fluid_parameters(s, heart)),
      aorta_initial_ml(start_aorta_at_ground_pressure(s, heart, grid, fluid)),
      forcing_parameters(fsei::forcing_parameters(s.fsei.forcing)),
      forcing(slabs, markers, forcing_parameters),
      fluid_module(fluid, markers, forcing, fluid_module_options(s.fsei)),
      tension(s, heart, group, resume.archive()),
      scales(output_scales(s, grid)) {}

}  // namespace systole::scene::fsei
