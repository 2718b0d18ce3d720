#include "solver/scene/lumped_scene.h"

#include "solver/lumped/simulate.h"

namespace systole::scene {

RunResult run_lumped(const config::Scenario& scenario, RunControl& control) {
  RunResult result = lumped::simulate(
      scenario, [&](const ProgressReport& report) { control.on_progress(report); },
      [&] { return control.cancel_requested(); });
  if (result.metrics["cancelled"] != 0) throw Cancelled();
  result.metrics.erase("cancelled");
  return result;
}

const std::vector<std::string>& lumped_metric_names() {
  static const std::vector<std::string> names{
      "ejection_fraction_percent", "cardiac_output_l_min", "stroke_volume_ml", "edv_ml", "esv_ml",
      "lv_peak_pressure_mmhg", "lv_peak_pressure_phase", "lv_end_diastolic_pressure_mmhg",
      "lv_end_systolic_pressure_mmhg", "aortic_pressure_max_mmhg", "aortic_pressure_min_mmhg",
      "aortic_pressure_mean_mmhg", "aortic_peak_flow_ml_s", "aortic_valve_open_phase",
      "aortic_valve_close_phase", "mitral_valve_open_phase", "mitral_valve_close_phase",
      "mitral_e_peak_flow_ml_s", "mitral_a_peak_flow_ml_s", "mitral_e_to_a_ratio", "heart_rate_bpm",
      "beats_simulated", "wall_time_s"};
  return names;
}

}  // namespace systole::scene
