#include "solver/scene/scene.h"

#include <chrono>

#include "solver/core/errors.h"
#include "solver/scene/registry.h"

namespace systole::scene {

const std::vector<std::string>& metric_names(const std::string& scene) {
  static const std::vector<std::string> none;
  const SceneEntry* entry = find_scene(scene);
  return entry ? entry->metric_names() : none;
}

RunResult run(const config::Scenario& scenario, RunControl& control) {
  const auto start = std::chrono::steady_clock::now();
  const SceneEntry* entry = find_scene(scenario.scene);
  if (!entry) {
    // parse_scenario() already rejects unimplemented scenes; this guards direct callers.
    std::string list;
    for (const SceneEntry& e : scene_registry()) list += (list.empty() ? "" : ", ") + std::string(e.name);
    throw InputError("scene '" + scenario.scene + "' is not implemented yet; implemented: " + list);
  }
  if (entry->check) {
    std::vector<std::string> problems;
    entry->check(scenario, problems);
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    if (!problems.empty()) throw InputError(all);
  }
  RunResult result = entry->run(scenario, control);
  result.metrics["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace systole::scene
