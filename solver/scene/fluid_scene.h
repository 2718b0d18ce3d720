#pragma once
// Scene "fluid": one verification flow of solver/fluid (fluid.verification_case) on
// MPI_COMM_WORLD; every rank calls it, the caller has called MPI_Init. Fields (velocity,
// pressure, vorticity at the end) in RunControl::output_directory() when asked for.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

RunResult run_fluid(const config::Scenario& scenario, RunControl& control);

// The metrics every fluid case reports (the error norms only where a case has an exact
// solution, so they are not listed).
const std::vector<std::string>& fluid_metric_names();

}  // namespace systole::scene
