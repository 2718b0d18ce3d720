#pragma once
// The composition root: a scenario names a scene, and the scene assembles exactly the
// physics modules it needs. The scenes are the rows of registry.h's table (name, run, metric
// names, checks, one line of description); solver/scene/README.md lists what each assembles
// and `systole-solve --list-scenes` prints the table. Every rank of an MPI worker calls run()
// with the same scenario; RunControl (run_control.h) is how the caller sees progress and asks
// for a stop.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

// Runs the scenario's scene to completion. Throws Cancelled, systole::InstabilityError (a run
// that blew up, with its diagnosis; never a NaN result), or systole::InputError (an unknown
// scene, or the problems its registry entry's check found, all of them in one message).
// Adds metrics["wall_time_s"] (this run's wall-clock time).
RunResult run(const config::Scenario& scenario, RunControl& control);

// The metric names a scene always reports (metrics.json keys): what campaigns may name as
// quantities of interest. Empty for an unknown scene. tests/unit/scene_test.cc checks them
// against real runs.
const std::vector<std::string>& metric_names(const std::string& scene);

}  // namespace systole::scene
