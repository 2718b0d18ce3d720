// Scene "electromechanics" (issue #8): a short coarse beat of the whole chain EP -> tension ->
// shells <-> 0-D circulation, the scheduler's limits, the forced-instability diagnosis and the
// scene's input checks. The calibrated full-resolution numbers: docs/electromechanics.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/scene/electromechanics_scene.h"
#include "solver/scene/scene.h"

namespace systole::scene {
namespace {

class Quiet final : public RunControl {
 public:
  void on_progress(const ProgressReport&) override { ++reports; }
  bool cancel_requested() override { return false; }
  int reports = 0;
};

// A coarse, short version of the default scenario (CI budget): 4 mm edges, monodomain EP at
// 0.1 ms, the 0-D LA, 2 ms synchronisation.
nlohmann::json coarse(int beats) {
  return {{"scene", "electromechanics"},
          {"beats", beats},
          {"geometry", {{"target_edge_mm", 4}}},
          {"electro", {{"model", "monodomain"}, {"time_step_ms", 0.1}}},
          {"electromechanics", {{"sync_step_ms", 1.0}, {"la_chamber", "lumped"}, {"field_interval_ms", 0}}}};
}

TEST(ElectromechanicsScene, CoarseBeatHoldsTheVolumeConstraintAndTheWallBuildsPressure) {
  const auto s = config::parse_scenario(coarse(1));
  Quiet control;
  const RunResult r = run_electromechanics(s, control);
  for (const auto& [key, value] : r.metrics) EXPECT_TRUE(std::isfinite(value)) << key;
  for (const auto& name : electromechanics_metric_names()) {
    if (name != "wall_time_s") EXPECT_TRUE(r.metrics.count(name)) << name;
  }
  // The iterated constraint: the wall holds the blood the valves let in, to the tolerance.
  // (Intervals that hit the pass limit, coupling.strong_max_iterations = 4, are counted and
  // must stay rare; the mismatch they leave is what the first assertion bounds.)
  EXPECT_LT(r.metrics.at("max_volume_mismatch_ml"), 0.01);
  EXPECT_LT(r.metrics.at("unconverged_intervals"), 0.01 * r.metrics.at("coupling_intervals"));
  // Multirate: no module ever stepped beyond its reported limit.
  EXPECT_LE(r.metrics.at("max_step_over_limit"), 1 + 1e-12);
  EXPECT_GT(r.metrics.at("structure_substeps"), r.metrics.at("coupling_intervals"));
  // One beat = the synchronisation points up to the one nearest T = 857.14 ms: 857 ms of EP.
  EXPECT_EQ(r.metrics.at("coupling_intervals"), 857);
  EXPECT_EQ(r.metrics.at("ep_steps"), 8570);
  // The active tension loads the closed cavity: the LV pressure rises well above its
  // end-diastolic value (Laplace: p ~ tau s kappa_f, docs/electromechanics.md).
  EXPECT_GT(r.metrics.at("lv_peak_pressure_mmhg"), r.metrics.at("lv_end_diastolic_pressure_mmhg") + 5);
  EXPECT_GE(r.metrics.at("edv_ml"), r.metrics.at("esv_ml"));
  EXPECT_GE(control.reports, 10);
  ASSERT_FALSE(r.series.empty());
  EXPECT_EQ(r.series[0].name, "time_s");
}

// Responses in the right direction on the coarse beat (issue #8). The scene is not calibrated
// (no ejection yet, docs/electromechanics.md), so the responses are read where this model
// already has them: the isovolumic peak pressure for the tension amplitude, the EDV for the
// passive stiffness, the onset of contraction (first time after 80 ms, before the earliest His
// stimulus, that the LV pressure exceeds its value at 80 ms by 3 mmHg) for the His delay.
TEST(ElectromechanicsScene, ResponsesToTensionStiffnessAndHisDelayGoTheRightWay) {
  Quiet control;
  auto run_with = [&](const nlohmann::json& patch) {
    nlohmann::json j = coarse(1);
    j.merge_patch(patch);
    return run_electromechanics(config::parse_scenario(j), control);
  };
  auto onset_ms = [](const RunResult& r) {
    const auto& t = r.series.at(0).values;
    const auto& p = r.series.at(1).values;  // lv_pressure_mmhg
    EXPECT_EQ(r.series.at(1).name, "lv_pressure_mmhg");
    std::size_t i0 = 0;
    while (i0 + 1 < t.size() && 1000 * t[i0] < 80) ++i0;
    for (std::size_t i = i0; i < p.size(); ++i)
      if (p[i] > p[i0] + 3) return 1000 * t[i];
    return -1.0;
  };
  const RunResult base = run_with(nlohmann::json::object());
  const RunResult strong = run_with({{"tissue", {{"active_tension_k_kpa", 47.9 * 1.5}}}});
  const RunResult stiff = run_with({{"electromechanics", {{"passive_stiffness_scale", 2000}}}});
  const RunResult late = run_with({{"av_delay_ms", 150}});
  std::printf("peak p: base %.2f, k_tau x1.5 %.2f mmHg | EDV: base %.3f, c x2 %.3f ml | onset: base %.1f, "
              "His +50 ms %.1f ms\n",
              base.metrics.at("lv_peak_pressure_mmhg"), strong.metrics.at("lv_peak_pressure_mmhg"),
              base.metrics.at("edv_ml"), stiff.metrics.at("edv_ml"), onset_ms(base), onset_ms(late));
  EXPECT_GT(strong.metrics.at("lv_peak_pressure_mmhg"), base.metrics.at("lv_peak_pressure_mmhg") + 2);
  EXPECT_LT(stiff.metrics.at("edv_ml"), base.metrics.at("edv_ml"));
  ASSERT_GT(onset_ms(base), 0);
  EXPECT_NEAR(onset_ms(late) - onset_ms(base), 50, 15);
}

TEST(ElectromechanicsScene, SyncStepNotAMultipleOfTheEpStepIsAnInputError) {
  nlohmann::json j = coarse(1);
  j["electromechanics"]["sync_step_ms"] = 0.25;
  j["electro"]["time_step_ms"] = 0.1;
  const auto s = config::parse_scenario(j);
  Quiet control;
  try {
    run_electromechanics(s, control);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("electromechanics.sync_step_ms"), std::string::npos) << e.what();
  }
}

TEST(ElectromechanicsScene, StepsEightTimesTheStructuresLimitStopWithADiagnosisNamingTheModule) {
  const auto s = config::parse_scenario(coarse(1));
  Quiet control;
  ElectromechanicsHooks hooks;
  hooks.step_limit_factor = 8;
  try {
    run_electromechanics(s, control, hooks);
    FAIL() << "expected an InstabilityError";
  } catch (const InstabilityError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("structure"), std::string::npos) << what;
    EXPECT_NE(what.find("node"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace systole::scene
