#pragma once
// The composition root: a scenario names a scene, and the scene assembles exactly the
// physics modules it needs. Today: "lumped" (0-D closed-loop left heart, solver/lumped),
// "analytic" (closed-form test functions), "fluid" (the verification flows of solver/fluid),
// "electro" (solver/electro alone), "mechanics" (solver/structure alone) and "ibm" (fluid +
// immersed boundary verification flows). solver/scene/README.md lists what each assembles.
// Every rank of an MPI worker calls run() with the same scenario; RunControl is how the
// caller sees progress and asks for a stop.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"

namespace systole::scene {

class RunControl {
 public:
  virtual ~RunControl() = default;
  // Called on every rank at the same points of the run (at least once per beat).
  virtual void on_progress(const ProgressReport& report) = 0;
  // Collective: every rank calls it at the same points and gets the same answer.
  virtual bool cancel_requested() = 0;
  // The directory this run's results are published from (the job's output directory); a scene
  // writes its large artifacts there (scene "fluid": fluid_fields.h5 + .xmf when asked for).
  // The same path on every rank (parallel HDF5 writes one shared file). Empty (the default):
  // the caller keeps no files; requested fields are then not written, with a note.
  virtual std::filesystem::path output_directory() { return {}; }
  // Where a scene that supports checkpoints (fsi, fsei) keeps them: a directory that outlives
  // this attempt of the job (a requeued job gets the same one). The scene resumes from a
  // checkpoint found there and writes new ones into it (fsei.checkpoint_interval_ms). The same
  // path on every rank. Empty (the default): no checkpoints.
  virtual std::filesystem::path checkpoint_directory() { return {}; }
  // Called on every rank, at the same points, after each checkpoint a scene writes (fsi, fsei):
  // `so_far` holds the series sampled from t = 0 to the checkpoint's time, as the finished run's
  // result would name them, and nothing else (no metrics: the run is not over). How a running
  // job's series is read (bench/coupling/fsei_case writes it as time_series.partial.csv). An
  // exception thrown here stops the run. Default: nothing.
  virtual void on_checkpoint(const RunResult& so_far) { (void)so_far; }
};

// Thrown by run() when RunControl::cancel_requested() said so; nothing is reported.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("run cancelled") {}
};

// Runs the scenario's scene to completion. Throws Cancelled, systole::InstabilityError (a run
// that blew up, with its diagnosis; never a NaN result), or systole::InputError.
// Adds metrics["wall_time_s"] (this run's wall-clock time).
RunResult run(const config::Scenario& scenario, RunControl& control);

// The metric names a scene always reports (metrics.json keys): what campaigns may name as
// quantities of interest. Empty for an unknown scene. tests/unit/scene_test.cc checks them
// against real runs.
const std::vector<std::string>& metric_names(const std::string& scene);

}  // namespace systole::scene
