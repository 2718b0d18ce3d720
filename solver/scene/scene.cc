#include "solver/scene/scene.h"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "solver/core/errors.h"
#include "solver/core/units.h"
#include "solver/fluid/verification_cases.h"
#include "solver/lumped/simulate.h"
#include "solver/scene/electro_scene.h"
#include "solver/scene/electromechanics_scene.h"
#include "solver/scene/fsei_scene.h"
#include "solver/scene/ibm_scene.h"
#include "solver/scene/mechanics_scene.h"
#include "uq/ishigami.h"

namespace systole::scene {
namespace {

// Scene "lumped": the closed-loop 0-D left heart alone (solver/lumped).
RunResult run_lumped(const config::Scenario& scenario, RunControl& control) {
  RunResult result = lumped::simulate(
      scenario, [&](const ProgressReport& report) { control.on_progress(report); },
      [&] { return control.cancel_requested(); });
  if (result.metrics["cancelled"] != 0) throw Cancelled();
  result.metrics.erase("cancelled");
  return result;
}

// Scene "analytic": one evaluation of a closed-form function (verification of campaigns).
RunResult run_analytic(const config::Scenario& scenario, RunControl& control) {
  if (control.cancel_requested()) throw Cancelled();
  const config::Analytic& a = scenario.analytic;
  const double x[3] = {a.x1, a.x2, a.x3};
  RunResult result;
  result.metrics["f"] = uq::ishigami(x, a.a, a.b);
  ProgressReport report;
  report.beat = 1;
  report.beats_total = 1;
  report.fraction = 1;
  report.latest_beat_metrics = result.metrics;
  control.on_progress(report);
  return result;
}

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

}  // namespace

const std::vector<std::string>& metric_names(const std::string& scene) {
  static const std::vector<std::string> lumped{
      "ejection_fraction_percent", "cardiac_output_l_min", "stroke_volume_ml", "edv_ml", "esv_ml",
      "lv_peak_pressure_mmhg", "lv_peak_pressure_phase", "lv_end_diastolic_pressure_mmhg",
      "lv_end_systolic_pressure_mmhg", "aortic_pressure_max_mmhg", "aortic_pressure_min_mmhg",
      "aortic_pressure_mean_mmhg", "aortic_peak_flow_ml_s", "aortic_valve_open_phase",
      "aortic_valve_close_phase", "mitral_valve_open_phase", "mitral_valve_close_phase",
      "mitral_e_peak_flow_ml_s", "mitral_a_peak_flow_ml_s", "mitral_e_to_a_ratio", "heart_rate_bpm",
      "beats_simulated", "wall_time_s"};
  static const std::vector<std::string> analytic{"f", "wall_time_s"};
  // Reported by every fluid case (the error norms only where a case has an exact solution).
  static const std::vector<std::string> fluid{
      "max_divergence_all_steps", "max_divergence_final", "mass_flux_relative_variation", "kinetic_energy_final",
      "dissipation_final", "max_viscosity", "steps", "end_time", "last_dt", "reynolds",
      "poisson_self_test_relative_divergence", "cells", "ranks", "fields_written", "wall_time_s"};
  static const std::vector<std::string> none;
  if (scene == "lumped") return lumped;
  if (scene == "analytic") return analytic;
  if (scene == "fluid") return fluid;
  if (scene == "electro") return electro_metric_names();
  if (scene == "mechanics") return mechanics_metric_names();
  if (scene == "electromechanics") return electromechanics_metric_names();
  if (scene == "ibm") return ibm_metric_names();
  if (scene == "fsi" || scene == "fsei") return fsei_metric_names();
  return none;
}

RunResult run(const config::Scenario& scenario, RunControl& control) {
  const auto start = std::chrono::steady_clock::now();
  RunResult result;
  if (scenario.scene == "lumped") {
    result = run_lumped(scenario, control);
  } else if (scenario.scene == "analytic") {
    result = run_analytic(scenario, control);
  } else if (scenario.scene == "fluid") {
    result = run_fluid(scenario, control);
  } else if (scenario.scene == "electro") {
    result = run_electro(scenario, control);
  } else if (scenario.scene == "mechanics") {
    result = run_mechanics(scenario, control);
  } else if (scenario.scene == "ibm") {
    result = run_ibm(scenario, control);
  } else if (scenario.scene == "electromechanics") {
    result = run_electromechanics(scenario, control);
  } else if (scenario.scene == "fsi" || scenario.scene == "fsei") {
    result = run_fsei(scenario, control);
  } else {
    // parse_scenario() already rejects unimplemented scenes; this guards direct callers.
    std::string list;
    for (const auto& name : config::implemented_scenes()) list += (list.empty() ? "" : ", ") + name;
    throw InputError("scene '" + scenario.scene + "' is not implemented yet; implemented: " + list);
  }
  result.metrics["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace systole::scene
