// Scenes "fsi" and "fsei": the composition root (fsei_scene.h). The run reads like the seed's
// Fig. 6: assemble the heart in its blood (coupled_heart.h), wire the coupled step
// (coupled_step.h), then advance it interval by interval, sampling the series (series.h),
// switching the valves' constraints (valve_switches.h), writing field frames (frames.h) and
// checkpoints (checkpoint.h), and finally the metrics (run_metrics.h).
#include <mpi.h>

#include <cmath>
#include <stdexcept>

#include "solver/core/errors.h"
#include "solver/scene/fsei/checkpoint.h"
#include "solver/scene/fsei/coupled_heart.h"
#include "solver/scene/fsei/coupled_step.h"
#include "solver/scene/fsei/frames.h"
#include "solver/scene/fsei/progress.h"
#include "solver/scene/fsei/run_metrics.h"
#include "solver/scene/fsei/series.h"
#include "solver/scene/fsei/valve_switches.h"
#include "solver/scene/fsei_scene.h"
#include "solver/scene/h5_dataset.h"

namespace systole::scene {
namespace {

using namespace fsei;

// The whole coupled state at a sample (checkpoint.h's layout): the fluid (collective), then the
// shells, the forcing's carried force, the EP, the scheduler, the series, the wall shear's
// accumulators and the frames' times as one archive written by rank 0. Then the caller sees the
// series so far (RunControl::on_checkpoint).
void write_checkpoint(const std::filesystem::path& root, const std::string& fingerprint, double t_ms,
                      const CoupledHeart& h, const CoupledStep& step, const SeriesRecorder& series,
                      const FieldFrames& frames, RunControl& control) {
  CheckpointDirectory dir(root);
  const std::filesystem::path next_dir = dir.begin();
  h.fluid.write_checkpoint(next_dir / "fluid.h5");
  int ok = 1;
  std::string error;
  if (is_rank_zero()) {
    try {
      StateArchive a;
      a.put_scalar("scene/time_ms", t_ms);
      h.group.export_state(a, "structure/");
      h.forcing.export_state(a, "ibm/");
      h.tension.export_state(a);
      step.export_state(a);
      series.export_state(a);
      if (frames.writing()) a.put("scene/field_times_ms", frames.frame_times_ms());
      write_state_file(next_dir / "state.h5", a, fingerprint);
    } catch (const std::exception& e) {
      ok = 0;
      error = e.what();
    }
  }
  MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!ok) throw std::runtime_error("fsei checkpoint at t = " + std::to_string(t_ms) + " ms: " + error);
  dir.publish();
  RunResult so_far;
  so_far.series = series.named();
  control.on_checkpoint(so_far);
}

// The end of the next interval the loop runs: the next sample, clipped at a valve switch (the LA
// stimulus, the LV stimulus, the limiter's end) and at a field frame (which is not a sample).
struct NextStop {
  double t_ms;
  double frame_ms;  // the next frame's time (1e300: none)
  bool frame_only;  // the stop is a frame before the next sample
};
NextStop next_stop(const config::Scenario& s, double t, double end_ms, const ValveSwitches& valves,
                   const FieldFrames& frames) {
  const double dt_sample = s.outputs.time_series_interval_ms;
  double next = std::min(end_ms, (std::floor(t / dt_sample + 1e-9) + 1) * dt_sample);
  for (double sw : valves.switch_times_after(t))
    if (sw > t + 1e-9 && sw < next) next = sw;
  const double frame = frames.next_after(t);
  const bool frame_only = frame < next - 1e-9;
  return {frame_only ? frame : next, frame, frame_only};
}

}  // namespace

RunResult run_fsei(const config::Scenario& s, RunControl& control) {
  check_fsei_scenario(s);
  const double end_ms = s.fsei.end_time_ms > 0 ? s.fsei.end_time_ms : s.beats * s.period_ms();
  const std::filesystem::path checkpoint_root = control.checkpoint_directory();
  const Resume resume = find_resume_point(s, checkpoint_root, end_ms);

  CoupledHeart h(s, resume);       // the modules (MODEL.md §1–2)
  CoupledStep step(h, resume);     // Fig. 6: tension → fluid → loads → shells → nodes
  SeriesRecorder series(s, h);
  ValveSwitches valves(h);
  double t = resume.time_ms();
  valves.apply(0);
  if (resume.directory) {
    series.resume(resume.state);
    valves.apply(t);
  } else {
    series.sample();
  }
  FieldFrames frames(h, control.output_directory(), resume);

  // checkpoints every fsei.checkpoint_interval_ms of simulated time (at a sample), and when the
  // run is cancelled (a worker that stops hands the job back at that point)
  const double checkpoint_ms = checkpoint_root.empty() ? 0.0 : s.fsei.checkpoint_interval_ms;
  double next_checkpoint_ms = checkpoint_ms > 0 ? (std::floor(t / checkpoint_ms + 1e-9) + 1) * checkpoint_ms : 1e300;
  const std::string fingerprint = scenario_fingerprint(s);
  RunFacts facts;
  facts.resumed_from_ms = resume.time_ms();
  try {
    while (t < end_ms - 1e-9) {
      const NextStop stop = next_stop(s, t, end_ms, valves, frames);
      step.advance_to(stop.t_ms);
      t = stop.t_ms;
      valves.apply(t);
      frames.write_if_due(t, stop.frame_ms);
      if (stop.frame_only) continue;
      series.sample();
      control.on_progress(progress_report(h, step, series, t, end_ms));
      if (control.cancel_requested()) {
        if (checkpoint_ms > 0) write_checkpoint(checkpoint_root, fingerprint, t, h, step, series, frames, control);
        throw Cancelled();
      }
      if (t >= next_checkpoint_ms - 1e-9 && t < end_ms - 1e-9) {
        write_checkpoint(checkpoint_root, fingerprint, t, h, step, series, frames, control);
        ++facts.checkpoints_written;
        next_checkpoint_ms = (std::floor(t / checkpoint_ms + 1e-9) + 1) * checkpoint_ms;
      }
    }
  } catch (const InstabilityError&) {
    frames.bodies_frame_on_stop(h.group.body(0).time_ms());  // the diagnosis in pictures
    throw;
  }
  facts.end_time_ms = t;
  return finish_result(h, step, series, frames, valves, facts, resume, control.output_directory(), checkpoint_root);
}

}  // namespace systole::scene
