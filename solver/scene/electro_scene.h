#pragma once
// Scene "electro": electrophysiology alone (solver/electro) on the procedural left heart's
// LV and LA walls, on an imported heart (electro.mesh = "manifest": the LV and/or LA bodies of
// a geometry::load_manifest manifest), or on a generated sheet / slab (scenario electro.mesh).
// See docs/electro.md for the outputs and their verification.
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/electro/tissue.h"
#include "solver/geometry/tri_mesh.h"
#include "solver/scene/scene.h"

namespace systole::scene {

RunResult run_electro(const config::Scenario& scenario, RunControl& control);

// The metrics run_electro always reports (whatever the mesh); the left heart adds per-chamber
// metrics (lv_*, la_*, av_activation_delay_ms) listed in docs/electro.md.
const std::vector<std::string>& electro_metric_names();

// The left heart's electrophysiology as the scenario sets it up, shared by the scenes that run
// EP on the procedural (or an imported) heart: the LV (domain 0) and LA (domain 1) myocardial
// walls of the given bodies (electro::from_surfaces, source_node filled), the cell models per
// domain, the seed's stimuli (Bachmann bundle at t = 0, His bundle at av_delay_ms, the Purkinje
// surrogate sites), every period, and the named probe nodes (his_bundle, lv_apex,
// bachmann_bundle where tagged).
struct EpProbe {
  std::string name;
  std::size_t node;
};
struct LeftHeartEp {
  electro::ElectroMesh mesh;
  electro::TissueOptions options;
  std::vector<EpProbe> probes;
  int lv_domain = 0, la_domain = 1;  // mesh domain of each chamber; -1 if absent (heart_ep)
};
LeftHeartEp left_heart_ep(const config::Scenario& scenario, const geometry::TriMesh& lv,
                          const geometry::TriMesh& la);
// The same for a heart that may lack one chamber (an imported LV alone or LA alone): a null
// body is left out, the other chamber becomes domain 0 (lv_domain / la_domain say which); at
// least one body must be given (InputError otherwise). left_heart_ep(s, lv, la) is
// heart_ep(s, &lv, &la).
LeftHeartEp heart_ep(const config::Scenario& scenario, const geometry::TriMesh* lv, const geometry::TriMesh* la);

// Loads electro.mesh_manifest (geometry::load_manifest) for scene "electro", mesh = "manifest".
// The path is read on the solver's machine; a relative path resolves against the solver's
// working directory, the files the manifest names against the manifest's folder. InputError
// naming electro.mesh_manifest when the file does not exist, is not a regular file, cannot be
// read or parsed, or has no body named "lv" or "la" (the names geometry::kLvBody / kLaBody).
std::vector<geometry::TriMesh> load_electro_manifest(const std::string& path);

}  // namespace systole::scene
