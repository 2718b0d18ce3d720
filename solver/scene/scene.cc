#include "solver/scene/scene.h"

#include <chrono>

#include "solver/core/errors.h"
#include "solver/lumped/simulate.h"

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

}  // namespace

RunResult run(const config::Scenario& scenario, RunControl& control) {
  const auto start = std::chrono::steady_clock::now();
  RunResult result;
  if (scenario.scene == "lumped") {
    result = run_lumped(scenario, control);
  } else {
    // parse_scenario() already rejects unimplemented scenes; this guards direct callers.
    throw InputError("scene '" + scenario.scene + "' is not implemented yet; implemented: lumped");
  }
  result.metrics["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace systole::scene
