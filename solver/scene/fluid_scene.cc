#include "solver/scene/fluid_scene.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solver/core/units.h"
#include "solver/fluid/verification_cases.h"

namespace systole::scene {
namespace {

// Scene "fluid": one verification flow of solver/fluid on MPI_COMM_WORLD (every rank calls
// run(); the caller has initialised MPI). Scales: the seed's d_m = 24 mm, U_m = 0.6 m/s
// (units.h), so Re = U_m d_m / nu and one time unit is 40 ms. nx, ny, nz are grid points
// (AFiD's convention): cells = n − 1.
fluid::FluidCaseSpec fluid_case_spec(const config::Scenario& scenario) {
  const config::Fluid& f = scenario.fluid;
  const double length_m = units::kSeedLength_m, velocity_m_s = units::kSeedVelocity_m_s;
  const double time_unit_ms = 1000 * length_m / velocity_m_s;
  fluid::FluidCaseSpec spec;
  spec.case_name = fluid::parse_verification_case(f.verification_case);
  spec.nx = f.nx - 1;
  spec.ny = f.ny - 1;
  spec.nz = f.nz - 1;
  spec.reynolds = velocity_m_s * length_m / f.kinematic_viscosity_m2_per_s;
  spec.end_time = f.end_time_ms / time_unit_ms;
  spec.cfl = f.cfl;
  spec.max_dt = f.max_dt_ms / time_unit_ms;
  spec.adaptive_dt = true;
  spec.womersley_number = f.womersley_number;
  // One sample (and one progress report / cancellation poll) per time-series interval.
  spec.samples = static_cast<int>(
      std::clamp(std::lround(f.end_time_ms / scenario.outputs.time_series_interval_ms), 1L, 100000L));
  spec.time_scale_s = length_m / velocity_m_s;
  spec.viscosity_model = f.viscosity_model;
  spec.subgrid_model = f.subgrid_model;
  spec.subgrid_constant = f.subgrid_constant;
  spec.carreau_yasuda = fluid::nondimensional(
      {f.carreau_yasuda_mu0_pa_s, f.carreau_yasuda_mu_inf_pa_s, f.carreau_yasuda_lambda_s, f.carreau_yasuda_n,
       f.carreau_yasuda_a, f.density_kg_per_m3},
      length_m, velocity_m_s);
  return spec;
}

}  // namespace

RunResult run_fluid(const config::Scenario& scenario, RunControl& control) {
  int mpi_ready = 0;
  MPI_Initialized(&mpi_ready);
  if (!mpi_ready) throw std::logic_error("scene 'fluid' needs MPI: the caller must call MPI_Init first");
  fluid::FluidCaseSpec spec = fluid_case_spec(scenario);
  // Fields: fluid.write_fields (all three) or outputs.fields naming some of them.
  const auto& listed = scenario.outputs.fields;
  auto named = [&](const char* name) { return std::find(listed.begin(), listed.end(), name) != listed.end(); };
  const bool by_list = named("velocity") || named("pressure") || named("vorticity");
  const bool want_fields = scenario.fluid.write_fields || by_list;
  spec.write_velocity = scenario.fluid.write_fields || named("velocity");
  spec.write_pressure = scenario.fluid.write_fields || named("pressure");
  spec.write_vorticity = scenario.fluid.write_fields || named("vorticity");
  if (want_fields) spec.output_dir = control.output_directory();
  RunResult result = fluid::run_verification_case(
      spec, MPI_COMM_WORLD, [&](const ProgressReport& report) { control.on_progress(report); },
      [&] { return control.cancel_requested(); });
  if (result.metrics["cancelled"] != 0) throw Cancelled();
  result.metrics.erase("cancelled");
  if (want_fields && spec.output_dir.empty())
    result.notes.push_back("fields were requested but the caller gave no output directory: none written");
  if (want_fields && !spec.output_dir.empty()) {
    result.notes.push_back("fields at t = " + std::to_string(result.metrics["end_time"] * spec.time_scale_s) +
                           " s in fluid_fields.h5 (+ fluid_fields.xmf for ParaView)");
    if (!scenario.outputs.field_phases.empty())
      result.notes.push_back("outputs.field_phases does not apply to scene 'fluid': fields are written at the end");
  }
  if (!scenario.outputs.time_series) result.series.clear();
  return result;
}

const std::vector<std::string>& fluid_metric_names() {
  static const std::vector<std::string> names{
      "max_divergence_all_steps", "max_divergence_final", "mass_flux_relative_variation", "kinetic_energy_final",
      "dissipation_final", "max_viscosity", "steps", "end_time", "last_dt", "reynolds",
      "poisson_self_test_relative_divergence", "cells", "ranks", "fields_written", "wall_time_s"};
  return names;
}

}  // namespace systole::scene
