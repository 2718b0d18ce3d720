#pragma once
// Scene "electro": electrophysiology alone (solver/electro) on the procedural left heart's
// LV and LA walls, on an imported heart (electro.mesh = "manifest": the LV and/or LA bodies of
// a geometry::load_manifest manifest), or on a generated sheet / slab (scenario electro.mesh).
// See docs/electro.md for the outputs and their verification.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/geometry/tri_mesh.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

RunResult run_electro(const config::Scenario& scenario, RunControl& control);

// The metrics run_electro always reports (whatever the mesh); the left heart adds per-chamber
// metrics (lv_*, la_*, av_activation_delay_ms) listed in docs/electro.md.
const std::vector<std::string>& electro_metric_names();

// Loads electro.mesh_manifest (geometry::load_manifest) for scene "electro", mesh = "manifest".
// The path is read on the solver's machine; a relative path resolves against the solver's
// working directory, the files the manifest names against the manifest's folder. InputError
// naming electro.mesh_manifest when the file does not exist, is not a regular file, cannot be
// read or parsed, or has no body named "lv" or "la" (the names geometry::kLvBody / kLaBody).
std::vector<geometry::TriMesh> load_electro_manifest(const std::string& path);

}  // namespace systole::scene
