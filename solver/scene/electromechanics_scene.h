#pragma once
// Scene "electromechanics": the beating left heart without 3-D fluid (issue #8,
// docs/electromechanics.md). EP (solver/electro) -> Nash–Panfilov tension -> LV (and LA) shells
// (solver/structure) <-> the 0-D circulation (solver/lumped) through the iterated cavity-volume
// constraint (solver/coupling/cavity_constraint.h), advanced by the multirate scheduler.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

// Test hooks: never set by a scenario.
struct ElectromechanicsHooks {
  // SchedulerOptions::step_limit_factor: substeps of factor x each module's reported limit (the
  // stability study shows the structure then stops itself with a diagnosis).
  double step_limit_factor = 1.0;
};

// The scene's own rules on the scenario (electromechanics.sync_step_ms a whole multiple of
// electro.time_step_ms; electro.mesh = "left_heart"), one line per problem appended to
// `problems`, each naming its field. run_electromechanics refuses a scenario that has any
// (InputError naming them all); registry.h lists it as the scene's check.
void check_electromechanics(const config::Scenario& scenario, std::vector<std::string>& problems);

RunResult run_electromechanics(const config::Scenario& scenario, RunControl& control,
                               const ElectromechanicsHooks& hooks = {});

// The metrics run_electromechanics always reports (metrics.json keys).
const std::vector<std::string>& electromechanics_metric_names();

}  // namespace systole::scene
