#include "solver/scene/registry.h"

#include "solver/scene/analytic_scene.h"
#include "solver/scene/electro_scene.h"
#include "solver/scene/electromechanics_scene.h"
#include "solver/scene/fluid_scene.h"
#include "solver/scene/fsei_scene.h"
#include "solver/scene/ibm_scene.h"
#include "solver/scene/lumped_scene.h"
#include "solver/scene/mechanics_scene.h"

namespace systole::scene {
namespace {

RunResult run_electromechanics_scene(const config::Scenario& scenario, RunControl& control) {
  return run_electromechanics(scenario, control);  // without test hooks
}

}  // namespace

const std::vector<SceneEntry>& scene_registry() {
  static const std::vector<SceneEntry> scenes{
      {"lumped", "the closed-loop 0-D left heart (elastance chambers, valves, Windkessel)",
       run_lumped, lumped_metric_names},
      {"analytic", "a closed-form test function (Ishigami) for verifying campaigns",
       run_analytic, analytic_metric_names},
      {"fluid", "a verification flow of the fluid solver (Taylor-Green 2-D/3-D, Poiseuille, Couette, Womersley)",
       run_fluid, fluid_metric_names},
      {"electro", "electrophysiology alone on the left heart's walls, an imported heart, a sheet or a slab",
       run_electro, electro_metric_names},
      {"mechanics", "the structure alone (sphere, sheet, LV, LV + LA, mitral leaflets) under pressure and tension",
       run_mechanics, mechanics_metric_names, config::check_mechanics_rules},
      {"ibm", "verification flows of the immersed boundary with the fluid (spheres, pipe, orifice plate)",
       run_ibm, ibm_metric_names},
      {"electromechanics", "EP -> active tension -> LV/LA shells <-> the 0-D circulation, without 3-D blood",
       run_electromechanics_scene, electromechanics_metric_names, check_electromechanics},
      {"fsi", "the left heart immersed in blood: fluid + IB + wall, valve and aorta shells, prescribed contraction",
       run_fsei, fsei_metric_names, config::check_fsei_rules},
      {"fsei", "scene fsi with the walls' tension from electrophysiology (the seed's whole model)",
       run_fsei, fsei_metric_names, config::check_fsei_rules},
  };
  return scenes;
}

const SceneEntry* find_scene(std::string_view name) {
  for (const SceneEntry& entry : scene_registry())
    if (entry.name == name) return &entry;
  return nullptr;
}

}  // namespace systole::scene
