#pragma once
// The composition root: a scenario names a scene, and the scene assembles exactly the
// physics modules it needs. Today: "lumped" (0-D closed-loop left heart, solver/lumped),
// "analytic" (closed-form test functions), "fluid" (the verification flows of solver/fluid),
// "electro" (solver/electro alone), "mechanics" (solver/structure alone) and "ibm" (fluid +
// immersed boundary verification flows). solver/scene/README.md lists what each assembles.
// Every rank of an MPI worker calls run() with the same scenario; RunControl is how the
// caller sees progress and asks for a stop (run_control.h).
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

// Runs the scenario's scene to completion. Throws Cancelled, systole::InstabilityError (a run
// that blew up, with its diagnosis; never a NaN result), or systole::InputError.
// Adds metrics["wall_time_s"] (this run's wall-clock time).
RunResult run(const config::Scenario& scenario, RunControl& control);

// The metric names a scene always reports (metrics.json keys): what campaigns may name as
// quantities of interest. Empty for an unknown scene. tests/unit/scene_test.cc checks them
// against real runs.
const std::vector<std::string>& metric_names(const std::string& scene);

}  // namespace systole::scene
