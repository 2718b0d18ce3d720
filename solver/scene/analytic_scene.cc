#include "solver/scene/analytic_scene.h"

#include "uq/ishigami.h"

namespace systole::scene {

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

const std::vector<std::string>& analytic_metric_names() {
  static const std::vector<std::string> names{"f", "wall_time_s"};
  return names;
}

}  // namespace systole::scene
