#pragma once
// The coupled scene's progress line: the latest sample's series (series.h's progress keys), what
// sets the fluid's step, the fastest shell node, the forcing's largest carried force and the
// coupling's iterations so far, so that a run that stops later leaves its trend.
#include "solver/core/run_result.h"
#include "solver/scene/fsei/coupled_step.h"
#include "solver/scene/fsei/series.h"

namespace systole::scene::fsei {

ProgressReport progress_report(const CoupledHeart& h, const CoupledStep& step, const SeriesRecorder& series,
                               double t_ms, double end_ms);

}  // namespace systole::scene::fsei
