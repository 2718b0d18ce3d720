// solver/scene: the registry agrees with config and is complete; every advertised metric name is
// really produced; a scene's checks run first; the analytic scene.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/scene/fsei_scene.h"
#include "solver/scene/registry.h"
#include "solver/scene/scene.h"

namespace systole::scene {
namespace {

class Quiet final : public RunControl {
 public:
  void on_progress(const ProgressReport&) override { ++reports; }
  bool cancel_requested() override { return cancel; }
  int reports = 0;
  bool cancel = false;
};

// Scene "fluid" runs on MPI_COMM_WORLD: MPI around the whole test program (1 rank).
class MpiEnvironment final : public ::testing::Environment {
 public:
  void SetUp() override { MPI_Init(nullptr, nullptr); }
  void TearDown() override { MPI_Finalize(); }
};
const auto* const mpi_environment = ::testing::AddGlobalTestEnvironment(new MpiEnvironment);

TEST(SceneRegistry, NamesAreConfigsImplementedScenes) {
  std::vector<std::string> names;
  for (const SceneEntry& e : scene_registry()) names.emplace_back(e.name);
  EXPECT_EQ(names, config::implemented_scenes());  // the same scenes, in the same order
  for (const SceneEntry& e : scene_registry()) {
    EXPECT_FALSE(e.description.empty()) << e.name;
    EXPECT_EQ(e.description.find('\n'), std::string_view::npos) << e.name << ": one line";
    ASSERT_NE(e.run, nullptr) << e.name;
    ASSERT_NE(e.metric_names, nullptr) << e.name;
    EXPECT_FALSE(e.metric_names().empty()) << e.name;
    EXPECT_EQ(find_scene(e.name), &e) << e.name << ": names are unique";
    EXPECT_EQ(&metric_names(std::string(e.name)), &e.metric_names()) << e.name;
  }
  EXPECT_EQ(find_scene("geometry"), nullptr);  // known to config, not implemented
  EXPECT_TRUE(metric_names("geometry").empty());
}

TEST(SceneRegistry, AnUnknownSceneIsAnInputErrorListingTheImplementedOnes) {
  config::Scenario s = config::default_scenario();
  s.scene = "geometry";
  Quiet control;
  try {
    run(s, control);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const auto& name : config::implemented_scenes()) EXPECT_NE(what.find(name), std::string::npos) << what;
  }
}

TEST(SceneRegistry, ASceneCheckRefusesTheScenarioBeforeItRunsNamingEveryProblem) {
  const SceneEntry* em = find_scene("electromechanics");
  ASSERT_NE(em, nullptr);
  ASSERT_NE(em->check, nullptr);
  // (parse_scenario refuses these at submit; a scenario built in code reaches the scene's check)
  auto s = config::parse_scenario({{"scene", "electromechanics"}});
  s.electro.mesh = "sheet";
  s.electro.time_step_ms = 0.1;
  s.electromechanics.sync_step_ms = 0.25;
  std::vector<std::string> problems;
  em->check(s, problems);
  EXPECT_EQ(problems.size(), 2u);
  Quiet control;
  try {
    run(s, control);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("electromechanics.sync_step_ms"), std::string::npos) << what;
    EXPECT_NE(what.find("electro.mesh"), std::string::npos) << what;
  }
  EXPECT_EQ(control.reports, 0);  // refused before anything ran
}

TEST(Scene, AdvertisedMetricsAreProduced) {
  for (const SceneEntry& entry : scene_registry()) {
    const std::string scene(entry.name);
    // fsi/fsei: minutes even at their coarsest; tests/coupling/fsei_scene_test.cc checks theirs.
    if (scene == "fsi" || scene == "fsei") continue;
    // The default fluid scenario is the seed's grid 1 (128x128x144 cells, ~30 s): this test
    // takes a small grid and a short run of the default case instead (deliberately).
    const nlohmann::json small_fluid{{"nx", 17}, {"ny", 17}, {"nz", 9}, {"end_time_ms", 8}};
    // The default electro scenario is the whole left heart over beats: a small sheet instead.
    const nlohmann::json small_electro{{"mesh", "sheet"}, {"mesh_size_x_mm", 4}, {"mesh_size_y_mm", 2},
                                       {"end_time_ms", 10}, {"model", "monodomain"}};
    // The default electromechanics scenario is beats of the 2 mm heart: one short beat of a 4 mm one.
    const nlohmann::json small_em{{"scene", scene},
                                  {"beats", 1},
                                  {"heart_rate_bpm", 240},
                                  {"geometry", {{"target_edge_mm", 4}}},
                                  {"electro", {{"model", "monodomain"}, {"time_step_ms", 0.1}}},
                                  {"electromechanics", {{"la_chamber", "lumped"}, {"field_interval_ms", 0}}}};
    config::Scenario s = config::parse_scenario(
        scene == "fluid"              ? nlohmann::json{{"scene", scene}, {"fluid", small_fluid}}
        : scene == "electro"          ? nlohmann::json{{"scene", scene}, {"electro", small_electro}}
        : scene == "electromechanics" ? small_em
                                      : nlohmann::json{{"scene", scene}});
    Quiet control;
    const RunResult r = run(s, control);
    ASSERT_FALSE(metric_names(scene).empty()) << scene;
    for (const auto& name : metric_names(scene)) EXPECT_TRUE(r.metrics.count(name)) << scene << ": " << name;
    EXPECT_GE(control.reports, 1);
  }
  EXPECT_EQ(metric_names("fsei"), fsei_metric_names());
  EXPECT_EQ(metric_names("fsi"), fsei_metric_names());
}

TEST(Scene, AnalyticIshigamiAtKnownPoints) {
  Quiet control;
  // f(pi/2, pi/2, 1) = 1 + a + b.
  const auto s = config::parse_scenario(
      {{"scene", "analytic"}, {"analytic", {{"x1", M_PI / 2}, {"x2", M_PI / 2}, {"x3", 1.0}}}});
  EXPECT_NEAR(run(s, control).metrics.at("f"), 1 + 7 + 0.1, 1e-12);
  control.cancel = true;
  EXPECT_THROW(run(s, control), Cancelled);
}

}  // namespace
}  // namespace systole::scene
