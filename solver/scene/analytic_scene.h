#pragma once
// Scene "analytic": one evaluation of a closed-form test function (uq/ishigami) at the
// scenario's analytic.x1..x3: the verification of campaigns, with known Sobol indices.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

RunResult run_analytic(const config::Scenario& scenario, RunControl& control);

// The metrics run_analytic always reports: f and wall_time_s.
const std::vector<std::string>& analytic_metric_names();

}  // namespace systole::scene
