#pragma once
// The coupled scene's result: the run's metrics (fsei_metric_names()), the per-beat metrics of
// every whole beat (fsei_beat_metrics), the phase averages over the beats after the first, the
// wall shear's phase average file, and the notes that say how the run was set up.
#include <filesystem>

#include "solver/core/run_result.h"
#include "solver/scene/fsei/coupled_step.h"
#include "solver/scene/fsei/frames.h"
#include "solver/scene/fsei/series.h"
#include "solver/scene/fsei/valve_switches.h"

namespace systole::scene::fsei {

struct RunFacts {
  double end_time_ms = 0;     // where the run ended
  double resumed_from_ms = 0;  // 0: from t = 0
  long checkpoints_written = 0;
};

RunResult finish_result(const CoupledHeart& h, const CoupledStep& step, SeriesRecorder& series,
                        const FieldFrames& frames, const ValveSwitches& valves, const RunFacts& facts,
                        const Resume& resume, const std::filesystem::path& output_directory,
                        const std::filesystem::path& checkpoint_root);

}  // namespace systole::scene::fsei
