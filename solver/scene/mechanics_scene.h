#pragma once
// Scene "mechanics": the structure alone (solver/structure), no fluid: a closed spherical
// shell, a clamped square sheet, or the procedural heart's LV and LA anchored at the valvular
// plane, under a prescribed cavity pressure and/or a uniform active fibre tension, both ramped
// over structure.pressure_ramp_ms. Outputs: node positions per outer step (structure.h5 +
// structure.xmf for ParaView), cavity volumes, strains, energies, metrics. See docs/structure.md.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/scene.h"

namespace systole::scene {

RunResult run_mechanics(const config::Scenario& scenario, RunControl& control);

// The metrics run_mechanics always reports (of the primary body: sphere, sheet or LV); the left
// heart adds lv_* and la_* volume metrics.
const std::vector<std::string>& mechanics_metric_names();

}  // namespace systole::scene
