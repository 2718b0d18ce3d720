#include "solver/scene/scene.h"

#include <chrono>

#include "solver/core/errors.h"
#include "solver/lumped/simulate.h"
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
  static const std::vector<std::string> none;
  if (scene == "lumped") return lumped;
  if (scene == "analytic") return analytic;
  return none;
}

RunResult run(const config::Scenario& scenario, RunControl& control) {
  const auto start = std::chrono::steady_clock::now();
  RunResult result;
  if (scenario.scene == "lumped") {
    result = run_lumped(scenario, control);
  } else if (scenario.scene == "analytic") {
    result = run_analytic(scenario, control);
  } else {
    // parse_scenario() already rejects unimplemented scenes; this guards direct callers.
    throw InputError("scene '" + scenario.scene + "' is not implemented yet; implemented: lumped, analytic");
  }
  result.metrics["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace systole::scene
