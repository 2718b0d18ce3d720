#pragma once
// RunControl: the caller's side of a scene's run (progress, cancellation, where files go);
// Cancelled: what a scene throws when the caller asked it to stop. Every scene takes a
// RunControl; scene.h (run, metric_names) and registry.h build on this header.
#include <filesystem>
#include <stdexcept>

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

// Thrown by a scene when RunControl::cancel_requested() said so; nothing is reported.
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("run cancelled") {}
};

}  // namespace systole::scene
