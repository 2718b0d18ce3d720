#pragma once
// Scene "mechanics": the structure alone (solver/structure), no fluid: a closed spherical
// shell, a clamped square sheet, the procedural heart's LV and LA anchored at the valvular
// plane (or its LV alone), or its two mitral leaflets anchored at the annulus (pressure = LV
// minus LA, closing them; the seed's limiter towards the LA), under a prescribed cavity
// pressure and/or a uniform active fibre tension, both ramped over structure.pressure_ramp_ms.
// The bodies advance in lockstep as a structure::BodyGroup with contact between them
// (structure.contact). Outputs: node positions per outer step (structure.h5 + structure.xmf for
// ParaView), cavity volumes, strains, energies, contact counts, metrics. See docs/structure.md.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

RunResult run_mechanics(const config::Scenario& scenario, RunControl& control);

// The metrics run_mechanics always reports (of the primary body: sphere, sheet, LV or anterior
// leaflet; contact_* over all bodies); several bodies or the LV add <body>_volume_*/_max_strain,
// the mitral leaflets leaflet_displacement_towards_la_mm, the bodies "lv" and "left_heart" the
// LV wall's readings (lv_wall_readings.h: lv_twist_deg, lv_gcs_percent, edge strains by direction).
const std::vector<std::string>& mechanics_metric_names();

}  // namespace systole::scene
