#pragma once
// The scene registry: one row per scene a scenario may name, and the only place that knows
// them all. scene::run() and scene::metric_names() (scene.h) look a scene up here;
// `systole-solve --list-scenes` prints the table. Adding a scene is one row in registry.cc
// (and its name in config::implemented_scenes(): tests/unit/scene_test.cc checks the two agree).
#include <string>
#include <string_view>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

struct SceneEntry {
  std::string_view name;         // scenario.scene
  std::string_view description;  // one line: what the scene assembles
  // Runs the scene to completion (the contract of scene::run, without wall_time_s).
  RunResult (*run)(const config::Scenario& scenario, RunControl& control);
  // The metrics the scene always reports (metrics.json keys; what campaigns may name).
  const std::vector<std::string>& (*metric_names)();
  // The scene's own checks of a scenario, one line per problem appended to `problems`, each
  // naming its field; scene::run() refuses a scenario with any (one InputError naming them all)
  // before the scene builds anything. nullptr: none. Rules that depend on the scenario alone
  // belong in config::check_consistency, run at submit (docs/architecture.md); a check here
  // is for a rule config does not hold (yet).
  void (*check)(const config::Scenario& scenario, std::vector<std::string>& problems) = nullptr;
};

// Every scene, in the order of config::implemented_scenes().
const std::vector<SceneEntry>& scene_registry();

// The entry named `name`, or nullptr.
const SceneEntry* find_scene(std::string_view name);

}  // namespace systole::scene
