#pragma once
// Scene "lumped": the closed-loop 0-D left heart alone (solver/lumped: elastance chambers,
// valves, Windkessel), beats until periodic or `beats`; metrics from solver/diagnostics.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

RunResult run_lumped(const config::Scenario& scenario, RunControl& control);

// The metrics run_lumped always reports (metrics.json keys).
const std::vector<std::string>& lumped_metric_names();

}  // namespace systole::scene
