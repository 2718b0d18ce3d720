#pragma once
// Scene "electro": electrophysiology alone (solver/electro) on the procedural left heart's
// LV and LA walls, or on a generated sheet / slab (scenario electro.mesh). See
// docs/electro.md for the outputs and their verification.
#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/scene.h"

namespace systole::scene {

RunResult run_electro(const config::Scenario& scenario, RunControl& control);

// The metrics run_electro always reports (whatever the mesh); the left heart adds per-chamber
// metrics (lv_*, la_*, av_activation_delay_ms) listed in docs/electro.md.
const std::vector<std::string>& electro_metric_names();

}  // namespace systole::scene
